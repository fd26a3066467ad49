# primlabel-bench-server: the labeling service over loopback gRPC against label_cloud in
# process, and cancellation latency on a 5M-point request.
if(TARGET primlabel_server)
  add_executable(primlabel-bench-server server_bench_main.cpp)
  target_include_directories(primlabel-bench-server PRIVATE ${CMAKE_SOURCE_DIR}/tests)
  target_link_libraries(primlabel-bench-server PRIVATE primlabel_server primlabel_scrape CLI11::CLI11
    nlohmann_json::nlohmann_json)
endif()
