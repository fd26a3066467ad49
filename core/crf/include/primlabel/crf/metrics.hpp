#pragma once
// Labelling quality: confusion matrix (counts), accuracy, per-class precision / recall / F1, and
// a plain-text rendering for reports.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace primlabel::crf {

struct ClassScores {
  double precision = 0.0;     // NaN when nothing was predicted as the class
  double recall = 0.0;        // NaN when the class never occurs in the truth
  double f1 = 0.0;            // NaN when precision or recall is
  std::uint64_t support = 0;  // points of the class in the truth
};

class ConfusionMatrix {
 public:
  // Rows are true classes, columns predicted classes, both in class_ids order; one extra column
  // counts predictions that are not one of the classes (e.g. the unknown label).
  explicit ConfusionMatrix(std::vector<std::uint32_t> class_ids);

  // Truth ids that are not one of the classes (or equal `ignore_truth`) are skipped.
  void add(std::uint32_t truth_id, std::uint32_t predicted_id, std::uint64_t count = 1);
  void add(std::span<const std::uint32_t> truth_ids, std::span<const std::uint32_t> predicted_ids,
           std::optional<std::uint32_t> ignore_truth = std::nullopt);

  // Adds another matrix's counts (e.g. over several scenes); throws std::invalid_argument when
  // its classes differ.
  void add(const ConfusionMatrix& other);

  int num_classes() const { return static_cast<int>(class_ids_.size()); }
  const std::vector<std::uint32_t>& class_ids() const { return class_ids_; }
  // predicted_index == num_classes() is the "other" column.
  std::uint64_t count(int truth_index, int predicted_index) const;
  std::uint64_t total() const { return total_; }
  std::uint64_t skipped() const { return skipped_; }

  double accuracy() const;  // NaN when empty
  ClassScores scores(int class_index) const;
  double macro_f1() const;  // mean F1 over classes that occur in the truth

  // Counts with per-class recall / precision / F1 and the overall accuracy. `names` (one per
  // class) label the rows; the ids are used when it is empty.
  std::string to_text(const std::vector<std::string>& names = {}) const;

 private:
  std::optional<int> index_of(std::uint32_t id) const;

  std::vector<std::uint32_t> class_ids_;
  std::vector<std::uint64_t> counts_;  // K x (K + 1), row-major
  std::uint64_t total_ = 0;
  std::uint64_t skipped_ = 0;
};

}  // namespace primlabel::crf
