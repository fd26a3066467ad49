#include "primlabel/ops/proc_self.hpp"

#include <charconv>
#include <vector>

namespace primlabel::ops {
namespace {

template <typename T>
std::optional<T> number(std::string_view text) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return value;
}

std::vector<std::string_view> blank_separated(std::string_view text, std::size_t at_most) {
  std::vector<std::string_view> fields;
  std::size_t pos = 0;
  while (fields.size() < at_most) {
    pos = text.find_first_not_of(" \t\n", pos);
    if (pos == std::string_view::npos) break;
    const std::size_t end = std::min(text.find_first_of(" \t\n", pos), text.size());
    fields.push_back(text.substr(pos, end - pos));
    pos = end;
  }
  return fields;
}

}  // namespace

std::optional<ProcStat> parse_proc_stat(std::string_view text) {
  const std::size_t comm_end = text.rfind(')');
  if (comm_end == std::string_view::npos || text.find('(') > comm_end) return std::nullopt;
  // Field 3 (state) is the first after the command name; we need up to field 24 (rss).
  const auto fields = blank_separated(text.substr(comm_end + 1), 22);
  if (fields.size() < 22) return std::nullopt;
  const auto field = [&fields](int number) { return fields[number - 3]; };
  const auto utime = number<std::uint64_t>(field(14));
  const auto stime = number<std::uint64_t>(field(15));
  const auto start = number<std::uint64_t>(field(22));
  const auto vsize = number<std::uint64_t>(field(23));
  const auto rss = number<std::int64_t>(field(24));
  if (!utime || !stime || !start || !vsize || !rss) return std::nullopt;
  return ProcStat{*utime, *stime, *start, *vsize, *rss};
}

std::optional<std::uint64_t> parse_boot_time(std::string_view proc_stat_text) {
  std::size_t pos = 0;
  while (pos < proc_stat_text.size()) {
    const std::size_t end = std::min(proc_stat_text.find('\n', pos), proc_stat_text.size());
    const std::string_view line = proc_stat_text.substr(pos, end - pos);
    if (line.starts_with("btime ")) {
      const auto fields = blank_separated(line, 3);
      if (fields.size() != 2) return std::nullopt;
      return number<std::uint64_t>(fields[1]);
    }
    pos = end + 1;
  }
  return std::nullopt;
}

}  // namespace primlabel::ops
