# The labeled-data component: taxonomy, synthetic scenes and scanners, labeled-cloud input, and
# the primlabel-synth tool. Included by core/CMakeLists.txt.
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/taxonomy.cpp
  ${CMAKE_CURRENT_LIST_DIR}/labeled_cloud.cpp
  ${CMAKE_CURRENT_LIST_DIR}/shapes.cpp
  ${CMAKE_CURRENT_LIST_DIR}/scene.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ground_truth.cpp
  ${CMAKE_CURRENT_LIST_DIR}/observed_creases.cpp
  ${CMAKE_CURRENT_LIST_DIR}/lms400.cpp
  ${CMAKE_CURRENT_LIST_DIR}/kinect.cpp
  ${CMAKE_CURRENT_LIST_DIR}/generate.cpp
)

add_executable(primlabel-synth
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/synth_main.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/cli_common.cpp)
target_link_libraries(primlabel-synth PRIVATE primlabel::core CLI11::CLI11 nlohmann_json::nlohmann_json)
