# Strict warnings and the optional sanitizer build, applied per target with
# canhil_target_defaults(<target>) so that third-party code is not affected.

add_library(canhil_options INTERFACE)
target_compile_options(canhil_options INTERFACE
  -Wall -Wextra -Wconversion -Wsign-conversion -Wshadow -Wpedantic
  -Wnon-virtual-dtor -Wold-style-cast -Wcast-align)
if(CANHIL_WERROR)
  target_compile_options(canhil_options INTERFACE -Werror)
endif()
if(CANHIL_SANITIZE)
  target_compile_options(canhil_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(canhil_options INTERFACE -fsanitize=address,undefined)
endif()

function(canhil_target_defaults target)
  target_link_libraries(${target} PRIVATE canhil_options)
endfunction()
