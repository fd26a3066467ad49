#include "primlabel/ops/process_collector.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>

#include "primlabel/ops/proc_self.hpp"

namespace primlabel::ops {
namespace {

// /proc files report a size of 0, so read until the end; they are small (/proc/stat grows with
// the CPUs and interrupts, to tens of KiB), but cap the read anyway.
std::optional<std::string> read_small_file(const std::string& path) {
  constexpr std::size_t kMaxBytes = 1 << 20;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string text;
  char block[4096];
  while (text.size() < kMaxBytes && in.read(block, sizeof block).gcount() > 0)
    text.append(block, std::size_t(in.gcount()));
  return text;
}

std::optional<double> count_open_fds(const std::string& fd_dir) {
  std::error_code error;
  std::filesystem::directory_iterator it(fd_dir, error), end;
  if (error) return std::nullopt;
  double count = 0;
  for (; it != end; it.increment(error)) {
    if (error) return std::nullopt;
    ++count;
  }
  return count;
}

prometheus::MetricFamily family(std::string name, std::string help, prometheus::MetricType type,
                                double value) {
  prometheus::MetricFamily result{std::move(name), std::move(help), type, {}};
  prometheus::ClientMetric metric;
  if (type == prometheus::MetricType::Counter)
    metric.counter.value = value;
  else
    metric.gauge.value = value;
  result.metric.push_back(std::move(metric));
  return result;
}

}  // namespace

ProcessCollector::ProcessCollector(std::string proc_dir, std::string proc_stat)
    : proc_dir_(std::move(proc_dir)), proc_stat_(std::move(proc_stat)) {}

std::vector<prometheus::MetricFamily> ProcessCollector::Collect() const {
  using prometheus::MetricType;
  std::vector<prometheus::MetricFamily> families;
  try {
    const long ticks_per_second = sysconf(_SC_CLK_TCK);
    const long page_bytes = sysconf(_SC_PAGESIZE);
    const std::optional<std::string> stat_text = read_small_file(proc_dir_ + "/stat");
    const std::optional<ProcStat> stat = stat_text ? parse_proc_stat(*stat_text) : std::nullopt;
    if (stat && ticks_per_second > 0 && page_bytes > 0) {
      families.push_back(family(
          "process_cpu_seconds_total", "Total user and system CPU time spent in seconds.",
          MetricType::Counter, double(stat->utime_ticks + stat->stime_ticks) / ticks_per_second));
      families.push_back(family("process_resident_memory_bytes", "Resident memory size in bytes.",
                                MetricType::Gauge, double(stat->resident_pages) * page_bytes));
      families.push_back(family("process_virtual_memory_bytes", "Virtual memory size in bytes.",
                                MetricType::Gauge, double(stat->virtual_bytes)));
      const std::optional<std::string> system_text = read_small_file(proc_stat_);
      if (const auto boot = system_text ? parse_boot_time(*system_text) : std::nullopt)
        families.push_back(family(
            "process_start_time_seconds", "Start time of the process since unix epoch in seconds.",
            MetricType::Gauge, double(*boot) + double(stat->start_ticks) / ticks_per_second));
    }
    if (const auto open = count_open_fds(proc_dir_ + "/fd"))
      families.push_back(
          family("process_open_fds", "Number of open file descriptors.", MetricType::Gauge, *open));
    rlimit limit{};
    if (getrlimit(RLIMIT_NOFILE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
      families.push_back(family("process_max_fds", "Maximum number of open file descriptors.",
                                MetricType::Gauge, double(limit.rlim_cur)));
  } catch (...) {
    // Out of memory, most likely; a scrape without process metrics beats a dead exposer.
  }
  return families;
}

}  // namespace primlabel::ops
