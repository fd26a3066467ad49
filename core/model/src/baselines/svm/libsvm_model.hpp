#pragma once
// A libsvm C-SVC / RBF model whose arrays this object owns, and libsvm's own text model format
// (what svm_save_model writes and svm_load_model reads) in memory. libsvm reads and writes that
// format through files only, and its reader trusts its input (a short or malformed file overflows
// its buffers), so models that may come from a file or the network are parsed and checked here.
// Values are written with 17 significant digits (libsvm writes support vectors with 8), so a
// model predicts bit-identically after a round trip; svm_load_model still reads the text.

#include <libsvm/svm.h>

#include <memory>
#include <string>
#include <vector>

namespace primlabel::svm::detail {

class LibsvmModel {
 public:
  // A copy of a trained model (its support vectors may point into training rows that die).
  static std::unique_ptr<LibsvmModel> copy_of(const svm_model& trained);

  // Throws std::invalid_argument with the line and the reason when `text` is not a C-SVC model
  // with an RBF kernel, or has support-vector indices outside 1..max_index.
  static std::unique_ptr<LibsvmModel> parse(const std::string& text, int max_index);

  std::string to_text() const;

  // For svm_predict / svm_predict_probability; points into this object.
  const svm_model& model() const { return view_; }

  LibsvmModel(const LibsvmModel&) = delete;
  LibsvmModel& operator=(const LibsvmModel&) = delete;

 private:
  LibsvmModel() = default;
  void bind();  // points view_ at the vectors below

  svm_model view_{};
  double gamma_ = 0;
  int nr_class_ = 0;
  std::vector<double> rho_, prob_a_, prob_b_;  // one per class pair; prob_* empty: no probabilities
  std::vector<int> label_, nr_sv_;             // per class
  std::vector<std::vector<double>> coef_;      // nr_class - 1 rows of total_sv coefficients
  std::vector<std::size_t> sv_start_;          // first node of each support vector
  std::vector<svm_node> nodes_;                // support vectors, each ended by index -1
  std::vector<double*> coef_rows_;
  std::vector<svm_node*> sv_rows_;
};

}  // namespace primlabel::svm::detail
