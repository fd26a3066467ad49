#include "primlabel/ros2/ros2_params_file.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace primlabel::ros2node {

namespace {

constexpr std::size_t kMaxFileBytes = std::size_t(1) << 20;

struct Line {
  int number = 0;  // 1-based, for messages
  std::size_t indent = 0;
  std::string text;  // without the indentation, the comment and trailing blanks
};

struct YamlNode {
  enum Kind { kNull, kScalar, kSequence, kMap } kind = kNull;
  int line = 0;
  std::string scalar;
  std::vector<std::string> items;
  std::vector<std::pair<std::string, YamlNode>> entries;
};

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

bool is_sequence_entry(const std::string& text) { return text == "-" || text.rfind("- ", 0) == 0; }

// Where a quoted scalar may start: at the start or after one of ":[,-" and blanks.
bool at_scalar_start(const std::string& text, std::size_t at) {
  std::size_t k = at;
  while (k > 0 && is_blank(text[k - 1])) --k;
  return k == 0 || text[k - 1] == ':' || text[k - 1] == '[' || text[k - 1] == ',' ||
         text[k - 1] == '-';
}

class Parser {
 public:
  Parser(std::string path, const std::string& content) : path_(std::move(path)) {
    std::istringstream in(content);
    std::string raw;
    int number = 0;
    bool any = false;
    while (std::getline(in, raw)) {
      ++number;
      if (!raw.empty() && raw.back() == '\r') raw.pop_back();
      const std::string text = without_comment(raw, number);
      const auto first = text.find_first_not_of(' ');
      if (first == std::string::npos) continue;
      if (is_blank(text[first]))
        fail(number, "a tab in the indentation (YAML indents with spaces)");
      Line line{number, first, trimmed(text)};
      if (line.indent == 0 && (line.text == "---" || line.text == "...")) {
        if (any || line.text == "...") fail(number, "one YAML document only");
        continue;
      }
      any = true;
      lines_.push_back(std::move(line));
    }
  }

  YamlNode document() {
    std::size_t i = 0;
    if (lines_.empty()) return {};
    if (lines_[0].indent != 0) fail(lines_[0].number, "the first key must not be indented");
    YamlNode root = block(i, 0);
    if (i != lines_.size()) fail(lines_[i].number, "indented like no key above it");
    return root;
  }

  [[noreturn]] void fail(int line, const std::string& why) const {
    throw std::invalid_argument("--params-file " + path_ + " line " + std::to_string(line) + ": " +
                                why);
  }

 private:
  std::string without_comment(const std::string& raw, int number) const {
    char quote = 0;
    for (std::size_t k = 0; k < raw.size(); ++k) {
      const char c = raw[k];
      if (quote == '"' && c == '\\') {
        ++k;
      } else if (quote && c == quote) {
        quote = 0;
      } else if (!quote && (c == '\'' || c == '"') && at_scalar_start(raw, k)) {
        quote = c;
      } else if (!quote && c == '#' && (k == 0 || is_blank(raw[k - 1]))) {
        return raw.substr(0, k);
      }
    }
    if (quote) fail(number, "a quoted scalar that does not end on its line");
    return raw;
  }

  YamlNode block(std::size_t& i, std::size_t indent) {
    return is_sequence_entry(lines_[i].text) ? sequence(i, indent) : map(i, indent);
  }

  YamlNode map(std::size_t& i, std::size_t indent) {
    YamlNode node;
    node.kind = YamlNode::kMap;
    node.line = lines_[i].number;
    while (i < lines_.size() && lines_[i].indent == indent) {
      const Line& line = lines_[i++];
      if (is_sequence_entry(line.text)) fail(line.number, "a list item where a key was expected");
      const auto [key, rest] = key_and_rest(line);
      for (const auto& entry : node.entries)
        if (entry.first == key) fail(line.number, "key '" + key + "' given twice");
      YamlNode child;
      child.line = line.number;
      if (!rest.empty()) {
        child = value(rest, line.number);
      } else if (i < lines_.size() && lines_[i].indent > indent) {
        child = block(i, lines_[i].indent);
      } else if (i < lines_.size() && lines_[i].indent == indent &&
                 is_sequence_entry(lines_[i].text)) {
        child = sequence(i, indent);  // PyYAML writes a key's list at the key's indentation
      }
      node.entries.emplace_back(key, std::move(child));
    }
    if (i < lines_.size() && lines_[i].indent > indent)
      fail(lines_[i].number, "indented more than its key");
    return node;
  }

  YamlNode sequence(std::size_t& i, std::size_t indent) {
    YamlNode node;
    node.kind = YamlNode::kSequence;
    node.line = lines_[i].number;
    while (i < lines_.size() && lines_[i].indent == indent && is_sequence_entry(lines_[i].text)) {
      const Line& line = lines_[i++];
      const std::string item = trimmed(line.text.substr(1));
      if (item.empty() || item[0] == '[' || is_sequence_entry(item) || has_key(item))
        fail(line.number, "a list of lists or maps (a ROS 2 parameter is a list of scalars)");
      node.items.push_back(scalar(item, line.number));
    }
    if (i < lines_.size() && lines_[i].indent > indent)
      fail(lines_[i].number, "indented more than its list");
    return node;
  }

  // Whether `text` (not quoted) holds "key: value" or ends with "key:".
  static bool has_key(const std::string& text) {
    if (text[0] == '\'' || text[0] == '"') return false;
    return text.find(": ") != std::string::npos || text.back() == ':';
  }

  std::pair<std::string, std::string> key_and_rest(const Line& line) const {
    const std::string& t = line.text;
    std::size_t colon;
    std::string key;
    if (t[0] == '\'' || t[0] == '"') {
      const auto close = t.find(t[0], 1);
      if (close == std::string::npos) fail(line.number, "a quoted key that does not end");
      key = scalar(t.substr(0, close + 1), line.number);
      colon = close + 1;
      if (colon >= t.size() || t[colon] != ':') fail(line.number, "expected ':' after the key");
    } else {
      colon = t.find(": ");
      if (colon == std::string::npos && t.back() == ':') colon = t.size() - 1;
      if (colon == std::string::npos || colon == 0)
        fail(line.number, "expected 'key: value' or 'key:'");
      key = trimmed(t.substr(0, colon));
      if (key[0] == '?' || key[0] == '&' || key[0] == '*' || key[0] == '!' || key[0] == '{' ||
          key[0] == '[')
        fail(line.number, "key '" + key + "' is beyond the YAML ROS 2 files use");
    }
    return {key, trimmed(t.substr(colon + 1))};
  }

  YamlNode value(const std::string& text, int number) const {
    YamlNode node;
    node.line = number;
    const char c = text[0];
    if (c == '{') fail(number, "a flow map {...}: write the map in block style, a key a line");
    if (c == '|' || c == '>') fail(number, "a multi-line scalar");
    if (c == '&' || c == '*' || c == '!') fail(number, "anchors, aliases and tags");
    if (c == '[') {
      node.kind = YamlNode::kSequence;
      node.items = flow_sequence(text, number);
      return node;
    }
    if (c != '\'' && c != '"' &&
        (text == "~" || text == "null" || text == "Null" || text == "NULL"))
      return node;  // no value
    if (has_key(text)) fail(number, "a second ':' in a plain value (quote the value)");
    node.kind = YamlNode::kScalar;
    node.scalar = scalar(text, number);
    return node;
  }

  std::vector<std::string> flow_sequence(const std::string& text, int number) const {
    if (text.back() != ']') fail(number, "a list [...] that does not end on its line");
    const std::string inner = trimmed(text.substr(1, text.size() - 2));
    std::vector<std::string> items;
    if (inner.empty()) return items;
    char quote = 0;
    std::string item;
    for (std::size_t k = 0; k <= inner.size(); ++k) {
      const char c = k < inner.size() ? inner[k] : ',';
      if (quote == '"' && c == '\\' && k + 1 < inner.size()) {
        item += c;
        item += inner[++k];
        continue;
      }
      if (quote && c == quote)
        quote = 0;
      else if (!quote && (c == '\'' || c == '"') && trimmed(item).empty())
        quote = c;
      else if (!quote && (c == '[' || c == '{'))
        fail(number, "a list of lists or maps");
      if (!quote && c == ',') {
        const std::string one = trimmed(item);
        if (one.empty()) fail(number, "an empty item in a list");
        items.push_back(scalar(one, number));
        item.clear();
      } else {
        item += c;
      }
    }
    return items;
  }

  std::string scalar(const std::string& text, int number) const {
    const char q = text[0];
    if (q != '\'' && q != '"') return text;
    if (text.size() < 2 || text.back() != q) fail(number, "a quoted scalar with text after it");
    const std::string inner = text.substr(1, text.size() - 2);
    std::string out;
    for (std::size_t k = 0; k < inner.size(); ++k) {
      const char c = inner[k];
      if (q == '\'' && c == '\'') {
        if (k + 1 >= inner.size() || inner[k + 1] != '\'') fail(number, "a lone ' inside '...'");
        out += '\'';
        ++k;
      } else if (q == '"' && c == '\\') {
        if (++k >= inner.size()) fail(number, "a '\\' at the end of \"...\"");
        switch (inner[k]) {
          case 'n':
            out += '\n';
            break;
          case 't':
            out += '\t';
            break;
          case '"':
            out += '"';
            break;
          case '\\':
            out += '\\';
            break;
          case '/':
            out += '/';
            break;
          default:
            fail(number, std::string("the escape \\") + inner[k] + " in \"...\"");
        }
      } else if (q == '"' && c == '"') {
        fail(number, "a '\"' inside \"...\" (escape it)");
      } else {
        out += c;
      }
    }
    return out;
  }

  std::string path_;
  std::vector<Line> lines_;
};

// The parameters under one node's ros__parameters, flattened with '.'.
void flatten(const Parser& parser, const YamlNode& node, const std::string& prefix,
             std::vector<FileParameter>& out) {
  for (const auto& [key, child] : node.entries) {
    const std::string name = prefix + key;
    switch (child.kind) {
      case YamlNode::kMap:
        flatten(parser, child, name + ".", out);
        break;
      case YamlNode::kScalar:
        out.push_back({name, child.scalar});
        break;
      case YamlNode::kSequence: {
        std::string text = "[";
        for (std::size_t k = 0; k < child.items.size(); ++k)
          text += (k ? ", " : "") + child.items[k];
        out.push_back({name, text + "]"});
        break;
      }
      case YamlNode::kNull:
        parser.fail(child.line, "parameter " + name + " has no value");
    }
  }
}

// The node entries of the file: nested keys down to ros__parameters, their path as a node name.
void node_entries(const Parser& parser, const YamlNode& node, const std::string& path,
                  const std::string& node_fqn, std::vector<FileParameter>& out) {
  for (const auto& [key, child] : node.entries) {
    if (key == "ros__parameters") {
      if (path.empty()) parser.fail(child.line, "ros__parameters outside a node's name");
      if (child.kind != YamlNode::kMap) parser.fail(child.line, "ros__parameters must be a map");
      if (node_key_matches(path, node_fqn)) flatten(parser, child, "", out);
      continue;
    }
    if (child.kind != YamlNode::kMap)
      parser.fail(child.line, "'" + key + "' must be a node's name with ros__parameters under it");
    std::string token = key;
    while (!token.empty() && token.front() == '/') token.erase(0, 1);
    while (!token.empty() && token.back() == '/') token.pop_back();
    node_entries(parser, child, path + "/" + token, node_fqn, out);
  }
}

std::vector<std::string> tokens(const std::string& name) {
  std::vector<std::string> out;
  std::string token;
  std::istringstream in(name);
  while (std::getline(in, token, '/'))
    if (!token.empty()) out.push_back(token);
  return out;
}

}  // namespace

bool node_key_matches(const std::string& key, const std::string& node_fqn) {
  const std::vector<std::string> k = tokens(key), n = tokens(node_fqn);
  // matches[i][j]: the key's first i tokens match the name's first j.
  std::vector<std::vector<char>> matches(k.size() + 1, std::vector<char>(n.size() + 1, 0));
  matches[0][0] = 1;
  for (std::size_t i = 1; i <= k.size(); ++i)
    for (std::size_t j = 0; j <= n.size(); ++j) {
      if (k[i - 1] == "**")
        matches[i][j] = matches[i - 1][j] || (j > 0 && matches[i][j - 1]);
      else if (j > 0)
        matches[i][j] = matches[i - 1][j - 1] && (k[i - 1] == "*" || k[i - 1] == n[j - 1]);
    }
  return matches[k.size()][n.size()];
}

std::vector<FileParameter> read_params_file(const std::string& path, const std::string& node_fqn) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::invalid_argument("--params-file " + path + ": not a readable file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("--params-file " + path + ": cannot read it");
  std::string content(kMaxFileBytes + 1, '\0');
  in.read(content.data(), static_cast<std::streamsize>(content.size()));
  if (in.bad()) throw std::invalid_argument("--params-file " + path + ": cannot read it");
  content.resize(static_cast<std::size_t>(in.gcount()));
  if (content.size() > kMaxFileBytes)
    throw std::invalid_argument("--params-file " + path + ": larger than 1 MiB");
  Parser parser(path, content);
  const YamlNode root = parser.document();
  std::vector<FileParameter> out;
  if (root.kind == YamlNode::kNull) return out;
  if (root.kind != YamlNode::kMap) parser.fail(root.line, "expected node names as keys");
  node_entries(parser, root, "", node_fqn, out);
  return out;
}

}  // namespace primlabel::ros2node
