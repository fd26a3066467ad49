# primlabel_library(NAME SOURCES src... [PUBLIC dep...] [PRIVATE dep...] [NO_HEADERS])
#
# One library of the project, in the folder that calls it: primlabel_NAME (alias primlabel::NAME),
# static, public headers under include/ (include/primlabel/...), private sources and headers under
# src/. Dependencies are declared here and nowhere else: a target sees the headers of what it links
# and of nothing more, because every library has an include root of its own. NO_HEADERS: a library
# whose headers are all generated (the protobuf and IDL libraries) has no include/ of its own.
#
# The boundary check: every public header is also compiled alone, in a translation unit of its
# own that sees only the library's public include root and its PUBLIC dependencies
# (primlabel_NAME_headers, part of the build and of the target primlabel_header_checks). A header
# that needs a library the target does not link publicly, or that depends on what was included
# before it, fails the build. tests/architecture checks the link graph itself.
function(primlabel_library name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "NO_HEADERS" "" "SOURCES;PUBLIC;PRIVATE")
  set(target primlabel_${name})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(primlabel::${name} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(NOT ARG_NO_HEADERS)
    target_include_directories(${target}
      PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  endif()
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  # Parallelism is ours (fixed blocks, OpenMP): Eigen's own multithreaded products would choose
  # their blocking from the thread count, and results must not depend on it.
  target_compile_definitions(${target} PRIVATE EIGEN_DONT_PARALLELIZE)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  set_property(GLOBAL APPEND PROPERTY PRIMLABEL_LIBRARIES ${target})
  if(NOT ARG_NO_HEADERS)
    primlabel_header_check(${target} ${CMAKE_CURRENT_SOURCE_DIR}/include)
  endif()
endfunction()

# Compiles each header under INCLUDE_ROOT alone (twice in one unit, so a missing include guard
# shows too) against only TARGET's public usage requirements.
function(primlabel_header_check target include_root)
  file(GLOB_RECURSE headers RELATIVE ${include_root} CONFIGURE_DEPENDS ${include_root}/*.hpp)
  if(NOT headers)
    return()
  endif()
  set(units "")
  foreach(header IN LISTS headers)
    string(MAKE_C_IDENTIFIER ${header} id)
    set(unit ${CMAKE_CURRENT_BINARY_DIR}/header_check/${id}.cpp)
    file(CONFIGURE OUTPUT ${unit} CONTENT "#include \"${header}\"\n#include \"${header}\"\n")
    list(APPEND units ${unit})
  endforeach()
  add_library(${target}_headers OBJECT ${units})
  # Usage requirements of the target only: its PRIVATE dependencies stay invisible.
  target_link_libraries(${target}_headers PRIVATE ${target})
  if(NOT TARGET primlabel_header_checks)
    add_custom_target(primlabel_header_checks)
  endif()
  add_dependencies(primlabel_header_checks ${target}_headers)
endfunction()
