# Project-wide target helpers: warnings and sanitizers are set here, once,
# on targets; never through CMAKE_CXX_FLAGS.

function(crackvis_configure_target target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Woverloaded-virtual -Wimplicit-fallthrough)
  if(CRACKVIS_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# crackvis_library(NAME area SOURCES ... ) -> target crackvis_<area>, alias crackvis::<area>
function(crackvis_library area)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  if(ARG_SOURCES)
    add_library(crackvis_${area} ${ARG_SOURCES})
    target_include_directories(crackvis_${area} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
    crackvis_configure_target(crackvis_${area})
  else()
    add_library(crackvis_${area} INTERFACE)
    target_include_directories(crackvis_${area} INTERFACE ${CMAKE_CURRENT_SOURCE_DIR}/include)
  endif()
  add_library(crackvis::${area} ALIAS crackvis_${area})
endfunction()

function(crackvis_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  crackvis_configure_target(${name})
endfunction()
