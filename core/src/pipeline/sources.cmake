# The labeling pipeline: describe a cloud, build its graph, train and apply a LabelModel; the
# primlabel-train and primlabel-eval tools. Included by core/CMakeLists.txt.
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/describe.cpp
  ${CMAKE_CURRENT_LIST_DIR}/duplicates.cpp
  ${CMAKE_CURRENT_LIST_DIR}/label_cloud.cpp
  ${CMAKE_CURRENT_LIST_DIR}/training.cpp
  ${CMAKE_CURRENT_LIST_DIR}/svm_model.cpp
  ${CMAKE_CURRENT_LIST_DIR}/curve_plot.cpp
  ${CMAKE_CURRENT_LIST_DIR}/confusion_plot.cpp
  ${CMAKE_CURRENT_LIST_DIR}/fig4.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mosd_report.cpp
  ${CMAKE_CURRENT_LIST_DIR}/table1.cpp
)

add_executable(primlabel-train
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/train_main.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/cli_common.cpp)
target_link_libraries(primlabel-train PRIVATE primlabel::core CLI11::CLI11)

add_executable(primlabel-eval
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/eval_main.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/cli_common.cpp)
target_link_libraries(primlabel-eval PRIVATE primlabel::core CLI11::CLI11 nlohmann_json::nlohmann_json)

