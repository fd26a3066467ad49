#pragma once
// What the kernel tells a process about itself under /proc (Linux), parsed from the files'
// text so the parsing can be tested on any input.

#include <cstdint>
#include <optional>
#include <string_view>

namespace primlabel::ops {

// The fields of /proc/<pid>/stat we use (proc(5): utime, stime, starttime in clock ticks,
// vsize in bytes, rss in pages).
struct ProcStat {
  std::uint64_t utime_ticks = 0;
  std::uint64_t stime_ticks = 0;
  std::uint64_t start_ticks = 0;  // after boot
  std::uint64_t virtual_bytes = 0;
  std::int64_t resident_pages = 0;
};

// nullopt when the text is not a stat line. The command name may hold blanks and parentheses,
// so fields are counted from its last ')'.
std::optional<ProcStat> parse_proc_stat(std::string_view text);

// The "btime" line of /proc/stat: boot time, seconds since the epoch; nullopt without one.
std::optional<std::uint64_t> parse_boot_time(std::string_view proc_stat_text);

}  // namespace primlabel::ops
