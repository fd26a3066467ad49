# Rendering: a software rasteriser writing PNG (libpng), colourings and legends, and the
# primlabel-render tool. Included by core/CMakeLists.txt.
target_sources(primlabel_core PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/raster.cpp
  ${CMAKE_CURRENT_LIST_DIR}/heatmap.cpp
  ${CMAKE_CURRENT_LIST_DIR}/render.cpp
  ${CMAKE_CURRENT_LIST_DIR}/colorize.cpp
)
target_link_libraries(primlabel_core PRIVATE PNG::PNG)

add_executable(primlabel-render
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/render_main.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/apps/cli_common.cpp)
target_link_libraries(primlabel-render PRIVATE primlabel::core CLI11::CLI11)
