#pragma once
// A confusion matrix as PNG: rows true classes, columns predicted classes (plus "other" when
// predictions fell outside the classes), cells coloured by the row-normalised share and printed
// with their counts, class names on both axes.

#include <string>
#include <vector>

#include "primlabel/crf/metrics.hpp"

namespace primlabel::research {

// `names` one per class (the ids when empty). Throws std::runtime_error naming the path when it
// cannot be written.
void write_confusion_png(const std::string& path, const crf::ConfusionMatrix& confusion,
                         const std::vector<std::string>& names, const std::string& title = "");

}  // namespace primlabel::research
