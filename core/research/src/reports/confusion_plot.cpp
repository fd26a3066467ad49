// Confusion-matrix PNG: a Heatmap of row-normalised shares with the counts in the cells.

#include "primlabel/research/confusion_plot.hpp"

#include <cmath>
#include <cstdio>

#include "primlabel/render/heatmap.hpp"

namespace primlabel::research {

void write_confusion_png(const std::string& path, const crf::ConfusionMatrix& confusion,
                         const std::vector<std::string>& names, const std::string& title) {
  const int k = confusion.num_classes();
  bool any_other = false;
  for (int t = 0; t < k; ++t) any_other = any_other || confusion.count(t, k) > 0;
  const int cols = any_other ? k + 1 : k;

  Heatmap heatmap;
  for (int c = 0; c < k; ++c)
    heatmap.row_names.push_back(names.empty() ? std::to_string(confusion.class_ids()[c])
                                              : names[c]);
  heatmap.column_names = heatmap.row_names;
  if (any_other) heatmap.column_names.push_back("other");
  for (int t = 0; t < k; ++t) {
    std::uint64_t row_total = 0;
    for (int p = 0; p <= k; ++p) row_total += confusion.count(t, p);
    for (int p = 0; p < cols; ++p) {
      const std::uint64_t n = confusion.count(t, p);
      heatmap.shades.push_back(row_total ? double(n) / double(row_total) : NAN);
      heatmap.cell_text.push_back(std::to_string(n));
    }
  }
  char accuracy[64];
  std::snprintf(accuracy, sizeof accuracy, "accuracy %.2f%%, %llu points",
                100.0 * confusion.accuracy(), static_cast<unsigned long long>(confusion.total()));
  heatmap.title = title.empty() ? accuracy : title + ": " + accuracy;
  heatmap.row_axis = "true class";
  heatmap.column_axis = "predicted class";
  draw_heatmap(heatmap).write_png(path);
}

}  // namespace primlabel::research
