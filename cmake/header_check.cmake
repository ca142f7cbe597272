# Each public header compiles alone: one generated translation unit per header under
# <module>/include/reprise/, each including its header twice (the include guard), built with the
# project's warnings as part of the normal build. A header that needs an include it lacks fails
# the build here instead of in a user's program.
file(GLOB_RECURSE reprise_public_headers CONFIGURE_DEPENDS
  ${PROJECT_SOURCE_DIR}/*/include/reprise/*.hpp)
set(reprise_header_sources "")
foreach(header ${reprise_public_headers})
  string(REGEX REPLACE "^.*/include/" "" relative ${header})
  string(REPLACE "/" "_" stem ${relative})
  string(REPLACE ".hpp" ".cpp" stem ${stem})
  set(source ${PROJECT_BINARY_DIR}/header_check/${stem})
  set(content "#include \"${relative}\"\n#include \"${relative}\"\n")
  if(EXISTS ${source})
    file(READ ${source} existing)
  endif()
  if(NOT existing STREQUAL content)
    file(WRITE ${source} "${content}")
  endif()
  list(APPEND reprise_header_sources ${source})
endforeach()
add_library(reprise_header_check OBJECT ${reprise_header_sources})
target_link_libraries(reprise_header_check PRIVATE reprise_core reprise_warp reprise_stereo
  reprise_codec reprise_server reprise_net reprise_gl reprise_gpu reprise_client)
