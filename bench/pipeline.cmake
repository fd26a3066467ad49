# primlabel-bench-pipeline: end-to-end points/s of pipeline::label_cloud (normals, FPFH, graph,
# inference) on a synthetic LMS400 scene and a synthetic Kinect frame. Included by
# bench/CMakeLists.txt (OPTIONAL).
add_executable(primlabel-bench-pipeline ${CMAKE_CURRENT_LIST_DIR}/pipeline_bench.cpp)
target_link_libraries(primlabel-bench-pipeline PRIVATE primlabel::core CLI11::CLI11
  nlohmann_json::nlohmann_json)
