# Strict warnings and the optional sanitizer build, applied per target with
# canhil_target_defaults(<target>) so that third-party code is not affected
# and installed targets carry no build-only dependency.

set(CANHIL_WARNINGS -Wall -Wextra -Wconversion -Wsign-conversion -Wshadow -Wpedantic -Wcast-align)
set(CANHIL_CXX_WARNINGS -Wnon-virtual-dtor -Wold-style-cast)
if(CANHIL_WERROR)
  list(APPEND CANHIL_WARNINGS -Werror)
endif()

function(canhil_target_defaults target)
  target_compile_options(${target} PRIVATE ${CANHIL_WARNINGS} $<$<COMPILE_LANGUAGE:CXX>:${CANHIL_CXX_WARNINGS}>)
  if(CANHIL_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
