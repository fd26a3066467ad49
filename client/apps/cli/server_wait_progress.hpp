#pragma once
// Progress while the server works on a sent scan (a 2M-point cloud takes seconds with nothing to
// count): "<what>: waiting for the server: 3.2 s" redrawn in place on a terminal once a second
// has passed, else one line after 2 s and then every 5 s, so logs stay short. Silent when quiet.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace primlabel::client::tools {

class ServerWaitProgress {
 public:
  ServerWaitProgress(bool quiet, std::string what);
  ~ServerWaitProgress();
  ServerWaitProgress(const ServerWaitProgress&) = delete;
  ServerWaitProgress& operator=(const ServerWaitProgress&) = delete;

  void start();  // the scan is sent: the wait begins (again, after a retry)
  void stop();   // the answer came, or the call failed: ends the line

 private:
  void run();

  const bool quiet_;
  const bool tty_;
  const std::string what_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool printed_ = false;
  std::chrono::steady_clock::time_point since_;
  std::thread thread_;
};

}  // namespace primlabel::client::tools
