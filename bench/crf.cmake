# primlabel-bench-crf: points/s of CRF inference (loopy BP sum/max-product, mean-field, node-only)
# on a synthetic 70k-point kNN-8 scene. Included by bench/CMakeLists.txt (OPTIONAL).
add_executable(primlabel-bench-crf ${CMAKE_CURRENT_LIST_DIR}/crf_bench.cpp)
# The scene generator is the header-only one the CRF tests use.
target_include_directories(primlabel-bench-crf PRIVATE ${CMAKE_SOURCE_DIR}/tests/crf)
target_link_libraries(primlabel-bench-crf PRIVATE primlabel::core CLI11::CLI11 nlohmann_json::nlohmann_json)
