#pragma once
// The standard process metrics of the Prometheus client libraries, read from /proc/self at
// every scrape:
//   process_cpu_seconds_total       counter, user + system CPU time
//   process_resident_memory_bytes   gauge
//   process_virtual_memory_bytes    gauge
//   process_open_fds                gauge, entries of /proc/self/fd
//   process_max_fds                 gauge, the soft RLIMIT_NOFILE
//   process_start_time_seconds      gauge, since the epoch
// A value that cannot be read (no /proc) is left out of the scrape; Collect never throws, since
// it runs on the exposer's thread.

#include <prometheus/collectable.h>
#include <prometheus/metric_family.h>

#include <string>
#include <vector>

namespace primlabel::ops {

class ProcessCollector : public prometheus::Collectable {
 public:
  // `proc_dir` is the process's /proc directory (tests point it elsewhere).
  explicit ProcessCollector(std::string proc_dir = "/proc/self",
                            std::string proc_stat = "/proc/stat");

  std::vector<prometheus::MetricFamily> Collect() const override;

 private:
  std::string proc_dir_;
  std::string proc_stat_;
};

}  // namespace primlabel::ops
