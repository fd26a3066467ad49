# Table-top pre-filter: dominant horizontal plane, table boundary, object clusters (issue 4/7).
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/voxel_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/plane_fit.cpp
  ${CMAKE_CURRENT_LIST_DIR}/convex_hull.cpp
  ${CMAKE_CURRENT_LIST_DIR}/euclidean_clusters.cpp
  ${CMAKE_CURRENT_LIST_DIR}/plane_grid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/stacked_split.cpp
  ${CMAKE_CURRENT_LIST_DIR}/occlusion_merge.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tabletop.cpp
  ${CMAKE_CURRENT_LIST_DIR}/segmentation_eval.cpp
)

# primlabel-tabletop: segments table scenes, scores them against mOSD labels, renders them.
add_executable(primlabel-tabletop ${CMAKE_CURRENT_SOURCE_DIR}/apps/tabletop_main.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/cli_common.cpp)
target_link_libraries(primlabel-tabletop PRIVATE primlabel::core CLI11::CLI11
  nlohmann_json::nlohmann_json)
