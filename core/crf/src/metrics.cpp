#include "primlabel/crf/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace primlabel::crf {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string format_score(double v) {
  if (std::isnan(v)) return "-";
  char buf[16];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

}  // namespace

ConfusionMatrix::ConfusionMatrix(std::vector<std::uint32_t> class_ids)
    : class_ids_(std::move(class_ids)), counts_(class_ids_.size() * (class_ids_.size() + 1), 0) {
  if (class_ids_.empty()) throw std::invalid_argument("ConfusionMatrix: no classes");
}

std::optional<int> ConfusionMatrix::index_of(std::uint32_t id) const {
  const auto it = std::find(class_ids_.begin(), class_ids_.end(), id);
  if (it == class_ids_.end()) return std::nullopt;
  return static_cast<int>(it - class_ids_.begin());
}

void ConfusionMatrix::add(std::uint32_t truth_id, std::uint32_t predicted_id, std::uint64_t count) {
  const auto t = index_of(truth_id);
  if (!t) {
    skipped_ += count;
    return;
  }
  const int p = index_of(predicted_id).value_or(num_classes());
  counts_[std::size_t(*t) * (num_classes() + 1) + p] += count;
  total_ += count;
}

void ConfusionMatrix::add(std::span<const std::uint32_t> truth_ids,
                          std::span<const std::uint32_t> predicted_ids,
                          std::optional<std::uint32_t> ignore_truth) {
  if (truth_ids.size() != predicted_ids.size())
    throw std::invalid_argument("ConfusionMatrix: truth and prediction sizes differ");
  for (std::size_t i = 0; i < truth_ids.size(); ++i) {
    if (ignore_truth && truth_ids[i] == *ignore_truth) {
      ++skipped_;
      continue;
    }
    add(truth_ids[i], predicted_ids[i]);
  }
}

void ConfusionMatrix::add(const ConfusionMatrix& other) {
  if (other.class_ids_ != class_ids_)
    throw std::invalid_argument("ConfusionMatrix: adding a matrix over other classes");
  for (std::size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  total_ += other.total_;
  skipped_ += other.skipped_;
}

std::uint64_t ConfusionMatrix::count(int truth_index, int predicted_index) const {
  return counts_[std::size_t(truth_index) * (num_classes() + 1) + predicted_index];
}

double ConfusionMatrix::accuracy() const {
  if (total_ == 0) return kNaN;
  std::uint64_t diagonal = 0;
  for (int k = 0; k < num_classes(); ++k) diagonal += count(k, k);
  return double(diagonal) / double(total_);
}

ClassScores ConfusionMatrix::scores(int k) const {
  ClassScores s;
  std::uint64_t predicted = 0;
  for (int t = 0; t < num_classes(); ++t) predicted += count(t, k);
  for (int p = 0; p <= num_classes(); ++p) s.support += count(k, p);
  const double tp = double(count(k, k));
  s.precision = predicted > 0 ? tp / double(predicted) : kNaN;
  s.recall = s.support > 0 ? tp / double(s.support) : kNaN;
  if (std::isnan(s.precision) || std::isnan(s.recall))
    s.f1 = kNaN;
  else
    s.f1 = s.precision + s.recall > 0.0 ? 2.0 * s.precision * s.recall / (s.precision + s.recall)
                                        : 0.0;
  return s;
}

double ConfusionMatrix::macro_f1() const {
  double sum = 0.0;
  int classes = 0;
  for (int k = 0; k < num_classes(); ++k) {
    const ClassScores s = scores(k);
    if (s.support == 0) continue;
    sum += std::isnan(s.f1) ? 0.0 : s.f1;  // never predicted: F1 counts as 0
    ++classes;
  }
  return classes > 0 ? sum / classes : kNaN;
}

std::string ConfusionMatrix::to_text(const std::vector<std::string>& names) const {
  const int k_count = num_classes();
  std::vector<std::string> labels(k_count);
  for (int k = 0; k < k_count; ++k)
    labels[k] = k < static_cast<int>(names.size()) ? names[k] : std::to_string(class_ids_[k]);
  std::size_t name_width = 10;  // "truth\pred"
  for (const auto& l : labels) name_width = std::max(name_width, l.size());
  std::size_t cell = 6;
  for (std::uint64_t c : counts_) cell = std::max(cell, std::to_string(c).size() + 1);
  for (int k = 0; k < k_count; ++k) cell = std::max(cell, std::to_string(class_ids_[k]).size() + 1);

  std::ostringstream out;
  const auto pad_left = [&](const std::string& s, std::size_t w) {
    out << std::string(w > s.size() ? w - s.size() : 0, ' ') << s;
  };
  const auto pad_right = [&](const std::string& s, std::size_t w) {
    out << s << std::string(w > s.size() ? w - s.size() : 0, ' ');
  };
  pad_right("truth\\pred", name_width);
  for (int k = 0; k < k_count; ++k) pad_left(std::to_string(class_ids_[k]), cell);
  pad_left("other", cell);
  out << "  recall precision     f1  support\n";
  for (int t = 0; t < k_count; ++t) {
    pad_right(labels[t], name_width);
    for (int p = 0; p <= k_count; ++p) pad_left(std::to_string(count(t, p)), cell);
    const ClassScores s = scores(t);
    out << "  ";
    pad_left(format_score(s.recall), 6);
    pad_left(format_score(s.precision), 10);
    pad_left(format_score(s.f1), 7);
    pad_left(std::to_string(s.support), 9);
    out << '\n';
  }
  out << "accuracy " << format_score(accuracy()) << "  macro-F1 " << format_score(macro_f1())
      << "  points " << total_;
  if (skipped_ > 0) out << "  (skipped " << skipped_ << ")";
  out << '\n';
  return out.str();
}

}  // namespace primlabel::crf
