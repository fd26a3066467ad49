#include "primlabel/scrape/exposition_parser.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>

namespace primlabel::scrape {
namespace {

class LineError : public std::invalid_argument {
 public:
  LineError(std::size_t line, const std::string& what)
      : std::invalid_argument("line " + std::to_string(line) + ": " + what) {}
};

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// [a-zA-Z_:][a-zA-Z0-9_:]*
bool is_valid_metric_name(std::string_view name) {
  if (name.empty()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':';
    if (!letter && !(i > 0 && c >= '0' && c <= '9')) return false;
  }
  return true;
}

// Cursor over one line of the exposition.
class LineReader {
 public:
  LineReader(std::string_view line, std::size_t number) : line_(line), number_(number) {}

  [[noreturn]] void fail(const std::string& what) const { throw LineError(number_, what); }
  bool at_end() const { return pos_ >= line_.size(); }
  char peek() const { return at_end() ? '\0' : line_[pos_]; }
  void skip_blanks() {
    while (!at_end() && is_blank(line_[pos_])) ++pos_;
  }
  void expect(char c) {
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++pos_;
  }
  // Characters up to the next blank (or `stop`), possibly none.
  std::string_view token(char stop = '\0') {
    const std::size_t start = pos_;
    while (!at_end() && !is_blank(line_[pos_]) && line_[pos_] != stop) ++pos_;
    return line_.substr(start, pos_ - start);
  }
  std::string_view identifier() {
    const std::size_t start = pos_;
    while (!at_end() && (std::isalnum(static_cast<unsigned char>(line_[pos_])) ||
                         line_[pos_] == '_' || line_[pos_] == ':'))
      ++pos_;
    return line_.substr(start, pos_ - start);
  }
  std::string quoted_value() {
    expect('"');
    std::string value;
    while (true) {
      if (at_end()) fail("unterminated label value");
      const char c = line_[pos_++];
      if (c == '"') return value;
      if (c != '\\') {
        value += c;
        continue;
      }
      if (at_end()) fail("unterminated escape in label value");
      const char escaped = line_[pos_++];
      if (escaped == 'n') {
        value += '\n';
      } else if (escaped == '\\' || escaped == '"') {
        value += escaped;
      } else {
        fail(std::string("invalid escape '\\") + escaped + "' in label value");
      }
    }
  }

 private:
  std::string_view line_;
  std::size_t number_;
  std::size_t pos_ = 0;
};

double parse_value(std::string_view text, const LineReader& reader) {
  if (text == "+Inf" || text == "Inf") return INFINITY;
  if (text == "-Inf") return -INFINITY;
  // prometheus-cpp writes NaN as "Nan"; Prometheus reads NaN in any case.
  if (text.size() == 3 && std::tolower(static_cast<unsigned char>(text[0])) == 'n' &&
      std::tolower(static_cast<unsigned char>(text[1])) == 'a' &&
      std::tolower(static_cast<unsigned char>(text[2])) == 'n')
    return NAN;
  if (text.starts_with('+')) text.remove_prefix(1);  // from_chars takes no '+'
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  // from_chars would also take "inf"/"nan" spellings Prometheus does not write; refuse them.
  const bool alphabetic_special =
      !text.empty() && std::isalpha(static_cast<unsigned char>(text[0]));
  if (error != std::errc() || end != text.data() + text.size() || alphabetic_special)
    reader.fail("invalid value '" + std::string(text) + "'");
  return value;
}

void check_comment(LineReader& reader) {
  reader.expect('#');
  reader.skip_blanks();
  const std::string_view keyword = reader.token();
  if (keyword != "HELP" && keyword != "TYPE") return;  // any other comment
  reader.skip_blanks();
  const std::string_view name = reader.token();
  if (!is_valid_metric_name(name)) reader.fail("invalid metric name in " + std::string(keyword));
  if (keyword == "HELP") return;
  reader.skip_blanks();
  const std::string_view type = reader.token();
  if (type != "counter" && type != "gauge" && type != "histogram" && type != "summary" &&
      type != "untyped")
    reader.fail("unknown metric type '" + std::string(type) + "'");
  reader.skip_blanks();
  if (!reader.at_end()) reader.fail("trailing text after TYPE");
}

Labels parse_labels(LineReader& reader) {
  Labels labels;
  reader.expect('{');
  reader.skip_blanks();
  while (reader.peek() != '}') {
    const std::string name(reader.identifier());
    if (name.empty() || !(std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_') ||
        name.find(':') != std::string::npos)
      reader.fail("invalid label name");
    reader.skip_blanks();
    reader.expect('=');
    reader.skip_blanks();
    std::string value = reader.quoted_value();
    if (!labels.emplace(name, std::move(value)).second)
      reader.fail("duplicate label '" + name + "'");
    reader.skip_blanks();
    if (reader.peek() == ',') {
      reader.expect(',');
      reader.skip_blanks();
    } else if (reader.peek() != '}') {
      reader.fail("expected ',' or '}' in labels");
    }
  }
  reader.expect('}');
  return labels;
}

Sample parse_sample(LineReader& reader) {
  Sample sample;
  sample.name = std::string(reader.identifier());
  if (!is_valid_metric_name(sample.name)) reader.fail("invalid metric name");
  if (reader.peek() == '{') sample.labels = parse_labels(reader);
  if (!is_blank(reader.peek())) reader.fail("expected a blank before the value");
  reader.skip_blanks();
  sample.value = parse_value(reader.token(), reader);
  reader.skip_blanks();
  if (!reader.at_end()) {
    const std::string_view timestamp = reader.token();
    long long ms = 0;
    const auto [end, error] =
        std::from_chars(timestamp.data(), timestamp.data() + timestamp.size(), ms);
    if (error != std::errc() || end != timestamp.data() + timestamp.size())
      reader.fail("invalid timestamp '" + std::string(timestamp) + "'");
    reader.skip_blanks();
    if (!reader.at_end()) reader.fail("trailing text after the timestamp");
  }
  return sample;
}

}  // namespace

std::vector<Sample> parse_exposition(std::string_view text) {
  std::vector<Sample> samples;
  std::size_t number = 0;
  while (!text.empty()) {
    ++number;
    const std::size_t newline = text.find('\n');
    std::string_view line = text.substr(0, newline);
    text.remove_prefix(newline == std::string_view::npos ? text.size() : newline + 1);
    if (line.ends_with('\r')) line.remove_suffix(1);
    LineReader reader(line, number);
    reader.skip_blanks();
    if (reader.at_end()) continue;
    if (reader.peek() == '#') {
      check_comment(reader);
      continue;
    }
    samples.push_back(parse_sample(reader));
  }
  return samples;
}

double sum_samples(const std::vector<Sample>& samples, std::string_view name, const Labels& match) {
  double sum = 0;
  for (const auto& sample : samples) {
    if (sample.name != name) continue;
    bool matches = true;
    for (const auto& [label, value] : match) {
      const auto it = sample.labels.find(label);
      matches = matches && it != sample.labels.end() && it->second == value;
    }
    if (matches) sum += sample.value;
  }
  return sum;
}

}  // namespace primlabel::scrape
