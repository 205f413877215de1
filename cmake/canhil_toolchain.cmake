# The build's tools beside the compiler, set by scripts/build.sh where installed.

# The linker (scripts/build.sh passes mold or lld where installed: a test
# suite's 40-odd programs link in a fraction of ld.bfd's time). Empty: the
# compiler's default.
set(CANHIL_LINKER "" CACHE STRING "Linker for canhil's programs and libraries: mold, lld, bfd or empty for the compiler's default")
if(CANHIL_LINKER)
  add_link_options(-fuse-ld=${CANHIL_LINKER})
endif()

# Unity builds (scripts/build.sh turns CMAKE_UNITY_BUILD on: a target's
# sources compiled a batch at a time, each header parsed once a batch). In
# one, every source is #included, and g++ then warns of a type from an
# anonymous namespace used in a class defined there, a warning meant for
# headers; a per-file build (the default configuration) still gives it.
if(CMAKE_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  list(APPEND CANHIL_CXX_WARNINGS -Wno-subobject-linkage)
endif()
