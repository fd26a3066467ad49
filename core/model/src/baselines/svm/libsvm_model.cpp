#include "libsvm_model.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string_view>
#include <type_traits>

namespace primlabel::svm::detail {

namespace {

// Far more classes than any taxonomy; bounds the header's allocations.
constexpr int kMaxClasses = 1000;

std::string format_double(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

// Whitespace-separated tokens of one line, no allocation beyond the vector.
std::vector<std::string_view> tokens_of(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

class Parser {
 public:
  explicit Parser(const std::string& text) : text_(text) {}

  // The next line, or false at the end of the text.
  bool next_line(std::string_view& line) {
    if (at_ >= text_.size()) return false;
    const std::size_t end = std::min(text_.find('\n', at_), text_.size());
    line = std::string_view(text_).substr(at_, end - at_);
    at_ = end + 1;
    ++line_number_;
    return true;
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("libsvm model, line " + std::to_string(line_number_) + ": " + what);
  }

  double real(std::string_view token, const char* what) const {
    double value = 0;
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (error != std::errc() || end != token.data() + token.size() || !std::isfinite(value))
      fail(std::string(what) + " '" + std::string(token) + "' is not a finite number");
    return value;
  }

  int integer(std::string_view token, const char* what, long long lo, long long hi) const {
    long long value = 0;
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (error != std::errc() || end != token.data() + token.size() || value < lo || value > hi)
      fail(std::string(what) + " '" + std::string(token) + "' is not an integer in " +
           std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(value);
  }

  // The values after the key, exactly `count` of them.
  std::vector<double> reals(const std::vector<std::string_view>& t, std::size_t count,
                            const char* what) const {
    if (t.size() - 1 != count)
      fail(std::string(what) + " has " + std::to_string(t.size() - 1) + " values, expected " +
           std::to_string(count));
    std::vector<double> out;
    for (std::size_t i = 1; i < t.size(); ++i) out.push_back(real(t[i], what));
    return out;
  }

 private:
  const std::string& text_;
  std::size_t at_ = 0;
  int line_number_ = 0;
};

}  // namespace

std::unique_ptr<LibsvmModel> LibsvmModel::copy_of(const svm_model& trained) {
  if (trained.param.svm_type != C_SVC || trained.param.kernel_type != RBF)
    throw std::invalid_argument("libsvm model: only C-SVC with an RBF kernel is supported");
  std::unique_ptr<LibsvmModel> m(new LibsvmModel());
  const int k = trained.nr_class, l = trained.l;
  const std::size_t pairs = std::size_t(k) * (k - 1) / 2;
  m->gamma_ = trained.param.gamma;
  m->nr_class_ = k;
  m->rho_.assign(trained.rho, trained.rho + pairs);
  if (trained.probA && trained.probB) {
    m->prob_a_.assign(trained.probA, trained.probA + pairs);
    m->prob_b_.assign(trained.probB, trained.probB + pairs);
  }
  m->label_.assign(trained.label, trained.label + k);
  m->nr_sv_.assign(trained.nSV, trained.nSV + k);
  for (int j = 0; j + 1 < k; ++j) m->coef_.emplace_back(trained.sv_coef[j], trained.sv_coef[j] + l);
  for (int i = 0; i < l; ++i) {
    m->sv_start_.push_back(m->nodes_.size());
    for (const svm_node* p = trained.SV[i]; p->index != -1; ++p) m->nodes_.push_back(*p);
    m->nodes_.push_back({-1, 0.0});
  }
  m->bind();
  return m;
}

std::unique_ptr<LibsvmModel> LibsvmModel::parse(const std::string& text, int max_index) {
  std::unique_ptr<LibsvmModel> m(new LibsvmModel());
  Parser parser(text);
  std::string_view line;
  std::set<std::string> seen;
  int total_sv = -1;
  bool rbf = false, c_svc = false, sv_section = false;
  auto pairs = [&] { return std::size_t(m->nr_class_) * (m->nr_class_ - 1) / 2; };
  auto need_classes = [&](const char* key) {
    if (!m->nr_class_) parser.fail(std::string(key) + " before nr_class");
  };
  while (!sv_section && parser.next_line(line)) {
    const std::vector<std::string_view> t = tokens_of(line);
    if (t.empty()) continue;
    const std::string key(t[0]);
    if (!seen.insert(key).second) parser.fail("'" + key + "' appears twice");
    if (key == "svm_type") {
      if (t.size() != 2 || t[1] != "c_svc") parser.fail("svm_type must be c_svc");
      c_svc = true;
    } else if (key == "kernel_type") {
      if (t.size() != 2 || t[1] != "rbf") parser.fail("kernel_type must be rbf");
      rbf = true;
    } else if (key == "gamma") {
      m->gamma_ = parser.reals(t, 1, "gamma")[0];
      if (m->gamma_ <= 0) parser.fail("gamma must be positive");
    } else if (key == "degree" || key == "coef0") {
      // Written for other kernels only; harmless for RBF.
    } else if (key == "nr_class") {
      if (t.size() != 2) parser.fail("nr_class takes one value");
      m->nr_class_ = parser.integer(t[1], "nr_class", 1, kMaxClasses);
    } else if (key == "total_sv") {
      if (t.size() != 2) parser.fail("total_sv takes one value");
      // Every support vector takes a line of at least two characters.
      total_sv = parser.integer(t[1], "total_sv", 0, (long long)(text.size() / 2));
    } else if (key == "rho") {
      need_classes("rho");
      m->rho_ = parser.reals(t, pairs(), "rho");
    } else if (key == "probA" || key == "probB") {
      need_classes(key.c_str());
      (key == "probA" ? m->prob_a_ : m->prob_b_) = parser.reals(t, pairs(), key.c_str());
    } else if (key == "label" || key == "nr_sv") {
      need_classes(key.c_str());
      if (t.size() - 1 != std::size_t(m->nr_class_))
        parser.fail(key + " has " + std::to_string(t.size() - 1) + " values, expected " +
                    std::to_string(m->nr_class_));
      std::vector<int>& values = key == "label" ? m->label_ : m->nr_sv_;
      for (std::size_t i = 1; i < t.size(); ++i)
        values.push_back(key == "label"
                             ? parser.integer(t[i], "label", std::numeric_limits<int>::min(),
                                              std::numeric_limits<int>::max())
                             : parser.integer(t[i], "nr_sv", 0, std::numeric_limits<int>::max()));
    } else if (key == "SV") {
      if (t.size() != 1) parser.fail("SV takes no values");
      sv_section = true;
    } else {
      parser.fail("unknown header entry '" + key + "'");
    }
  }
  if (!sv_section) parser.fail("no SV section (truncated?)");
  for (const char* required :
       {"svm_type", "kernel_type", "gamma", "nr_class", "total_sv", "rho", "label", "nr_sv"})
    if (!seen.count(required)) parser.fail(std::string("the header has no ") + required);
  if (c_svc != rbf) parser.fail("incomplete header");
  if (seen.count("probA") != seen.count("probB")) parser.fail("probA without probB or back");
  if (std::set<int>(m->label_.begin(), m->label_.end()).size() != m->label_.size())
    parser.fail("labels repeat");
  if (std::accumulate(m->nr_sv_.begin(), m->nr_sv_.end(), 0LL) != total_sv)
    parser.fail("nr_sv does not add up to total_sv " + std::to_string(total_sv));

  // Each support vector line holds nr_class - 1 coefficients of at least two characters: bounds
  // the allocation below by the text's size.
  if (std::uint64_t(total_sv) * std::uint64_t(std::max(m->nr_class_ - 1, 1)) * 2 > text.size())
    parser.fail("total_sv " + std::to_string(total_sv) + " is more than the text holds");
  m->coef_.assign(std::size_t(m->nr_class_ - 1), std::vector<double>(std::size_t(total_sv)));
  int parsed = 0;
  while (parser.next_line(line)) {
    const std::vector<std::string_view> t = tokens_of(line);
    if (t.empty()) continue;
    if (parsed == total_sv) parser.fail("more support vectors than total_sv");
    if (t.size() < std::size_t(m->nr_class_ - 1))
      parser.fail("a support vector needs " + std::to_string(m->nr_class_ - 1) + " coefficients");
    for (int j = 0; j + 1 < m->nr_class_; ++j)
      m->coef_[j][parsed] = parser.real(t[j], "coefficient");
    m->sv_start_.push_back(m->nodes_.size());
    int previous = 0;
    for (std::size_t i = std::size_t(m->nr_class_ - 1); i < t.size(); ++i) {
      const std::size_t colon = t[i].find(':');
      if (colon == std::string_view::npos)
        parser.fail("'" + std::string(t[i]) + "' is no index:value");
      const int index = parser.integer(t[i].substr(0, colon), "feature index", 1, max_index);
      if (index <= previous) parser.fail("feature indices must increase");
      previous = index;
      m->nodes_.push_back({index, parser.real(t[i].substr(colon + 1), "feature value")});
    }
    m->nodes_.push_back({-1, 0.0});
    ++parsed;
  }
  if (parsed != total_sv)
    parser.fail("only " + std::to_string(parsed) + " of " + std::to_string(total_sv) +
                " support vectors (truncated?)");
  m->bind();
  return m;
}

void LibsvmModel::bind() {
  view_ = svm_model{};
  view_.param.svm_type = C_SVC;
  view_.param.kernel_type = RBF;
  view_.param.gamma = gamma_;
  view_.param.probability = prob_a_.empty() ? 0 : 1;
  view_.nr_class = nr_class_;
  view_.l = static_cast<int>(sv_start_.size());
  coef_rows_.clear();
  for (auto& row : coef_) coef_rows_.push_back(row.data());
  sv_rows_.clear();
  for (std::size_t start : sv_start_) sv_rows_.push_back(nodes_.data() + start);
  view_.SV = sv_rows_.data();
  view_.sv_coef = coef_rows_.data();
  view_.rho = rho_.data();
  // libsvm tells probability models by non-null probA / probB (a one-class model has none).
  view_.probA = prob_a_.empty() ? nullptr : prob_a_.data();
  view_.probB = prob_b_.empty() ? nullptr : prob_b_.data();
  view_.label = label_.data();
  view_.nSV = nr_sv_.data();
  view_.free_sv = 0;
}

std::string LibsvmModel::to_text() const {
  // The layout of libsvm 3.24's svm_save_model.
  std::string out;
  auto line = [&out](const char* key, const auto& values) {
    out += key;
    for (const auto v : values) {
      out += ' ';
      if constexpr (std::is_floating_point_v<decltype(v)>)
        out += format_double(v);
      else
        out += std::to_string(v);
    }
    out += '\n';
  };
  out += "svm_type c_svc\nkernel_type rbf\n";
  line("gamma", std::vector<double>{gamma_});
  line("nr_class", std::vector<int>{nr_class_});
  line("total_sv", std::vector<std::size_t>{sv_start_.size()});
  line("rho", rho_);
  line("label", label_);
  if (!prob_a_.empty()) {
    line("probA", prob_a_);
    line("probB", prob_b_);
  }
  line("nr_sv", nr_sv_);
  out += "SV\n";
  for (std::size_t i = 0; i < sv_start_.size(); ++i) {
    for (const auto& row : coef_) {
      out += format_double(row[i]);
      out += ' ';
    }
    for (const svm_node* p = nodes_.data() + sv_start_[i]; p->index != -1; ++p) {
      out += std::to_string(p->index);
      out += ':';
      out += format_double(p->value);
      out += ' ';
    }
    out += '\n';
  }
  return out;
}

}  // namespace primlabel::svm::detail
