#pragma once
// One field of /proc/<pid>/status as a number ("VmHWM" and "VmRSS" in kB, "Threads"), for the
// suites that bound a server's memory and threads; -1 when the field or the process is missing.

#include <fstream>
#include <string>

namespace primlabel::testing {

inline long proc_status(const std::string& field, const std::string& pid = "self") {
  std::ifstream in("/proc/" + pid + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  return -1;
}

}  // namespace primlabel::testing
