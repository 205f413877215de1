# Strict warnings and the optional sanitizer builds (CANHIL_SANITIZE: ON for
# ASan + UBSan, thread for TSan), applied per target with
# canhil_target_defaults(<target>) so that third-party code is not affected
# and installed targets carry no build-only dependency.

set(CANHIL_WARNINGS -Wall -Wextra -Wconversion -Wsign-conversion -Wshadow -Wpedantic -Wcast-align)
set(CANHIL_CXX_WARNINGS -Wnon-virtual-dtor -Wold-style-cast)
# g++ 12 warns falsely with -Wrestrict inside std::string at -O3 (GCC bug
# 105651, fixed in g++ 13): `"x" + std::string(...)` in a Release build. The
# warning has no true positive in canhil to lose; later versions keep it.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  list(APPEND CANHIL_CXX_WARNINGS -Wno-restrict)
endif()
# Warnings as errors only when asked (the project's scripts and CI ask): a
# packager or a team building canhil with its own compiler gets warnings, not
# a failed build.
if(CANHIL_WERROR)
  list(APPEND CANHIL_WARNINGS -Werror)
endif()

function(canhil_target_defaults target)
  target_compile_options(${target} PRIVATE ${CANHIL_WARNINGS} $<$<COMPILE_LANGUAGE:CXX>:${CANHIL_CXX_WARNINGS}>)
  if(CANHIL_SANITIZE STREQUAL "thread")
    target_compile_options(${target} PRIVATE -fsanitize=thread -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=thread)
  elseif(CANHIL_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# canhil_preload_library(<target> <output name> SOURCES ... [INCLUDES ...]): a
# library preloaded (LD_PRELOAD) into programs canhil did not build (the time
# shim, the user-space bus): no sanitizer (a sanitizer runtime must come first
# in a process, and the team's programs have none), nothing of canhil's but
# base's header-only preload plumbing (libc only), C++ without exceptions,
# only its intercepting calls visible; installed in LIBDIR.
function(canhil_preload_library target output)
  cmake_parse_arguments(P "" "" "SOURCES;INCLUDES" ${ARGN})
  add_library(${target} SHARED ${P_SOURCES})
  target_include_directories(${target} PRIVATE ${P_INCLUDES})
  target_compile_options(${target} PRIVATE ${CANHIL_WARNINGS} ${CANHIL_CXX_WARNINGS} -fno-exceptions)
  target_link_libraries(${target} PRIVATE canhil::base ${CMAKE_DL_LIBS})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME ${output} CXX_VISIBILITY_PRESET hidden
                                             VISIBILITY_INLINES_HIDDEN ON)
  include(GNUInstallDirs)
  install(TARGETS ${target} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
endfunction()
