# primlabel-bench-tabletop: ms per scene of the table-top pre-filter, optionally against PCL's
# SACSegmentation + ConvexHull + ExtractPolygonalPrismData + EuclideanClusterExtraction.
# Included by bench/CMakeLists.txt (include(${CMAKE_CURRENT_SOURCE_DIR}/tabletop.cmake)).
add_executable(primlabel-bench-tabletop ${CMAKE_CURRENT_LIST_DIR}/tabletop_bench_main.cpp)
target_link_libraries(primlabel-bench-tabletop PRIVATE primlabel::core CLI11::CLI11
  nlohmann_json::nlohmann_json)

if(PRIMLABEL_WITH_PCL)
  # As in bench/CMakeLists.txt: Debian 12's VTK config names MPI::MPI_C without finding MPI.
  if(NOT TARGET MPI::MPI_C)
    add_library(MPI::MPI_C INTERFACE IMPORTED)
  endif()
  find_package(PCL 1.13 QUIET COMPONENTS common segmentation search kdtree sample_consensus
               surface filters)
endif()
if(PCL_FOUND AND PCL_SEGMENTATION_FOUND AND PCL_SURFACE_FOUND)
  set(PRIMLABEL_TABLETOP_PCL_LIBS ${PCL_COMMON_LIBRARIES} ${PCL_SEARCH_LIBRARIES}
      ${PCL_KDTREE_LIBRARIES} ${PCL_SAMPLE_CONSENSUS_LIBRARIES} ${PCL_SURFACE_LIBRARIES}
      ${PCL_FILTERS_LIBRARIES} ${PCL_SEGMENTATION_LIBRARIES})
  if(TARGET FLANN::FLANN)
    list(APPEND PRIMLABEL_TABLETOP_PCL_LIBS FLANN::FLANN)
  endif()
  add_library(primlabel_tabletop_pcl_peer STATIC ${CMAKE_CURRENT_LIST_DIR}/tabletop_pcl_peer.cpp)
  target_include_directories(primlabel_tabletop_pcl_peer PRIVATE ${PCL_INCLUDE_DIRS})
  target_compile_definitions(primlabel_tabletop_pcl_peer PRIVATE ${PCL_DEFINITIONS})
  target_link_libraries(primlabel_tabletop_pcl_peer PRIVATE ${PRIMLABEL_TABLETOP_PCL_LIBS}
                        primlabel::core)
  target_link_libraries(primlabel-bench-tabletop PRIVATE primlabel_tabletop_pcl_peer)
  target_compile_definitions(primlabel-bench-tabletop PRIVATE PRIMLABEL_HAVE_PCL=1)
else()
  message(STATUS "primlabel-bench-tabletop: PCL segmentation/surface not found, no comparison")
endif()
