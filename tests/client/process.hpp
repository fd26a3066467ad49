#pragma once
// A child process for end-to-end tests: started with its output in a log file, always killed
// (SIGKILL) when the object dies, so a failing test never leaves a server behind.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace primlabel::test {

class Process {
 public:
  // Starts `argv` with stdout and stderr appended to `log`, stdin from `input` (or /dev/null).
  Process(std::vector<std::string> argv, std::string log, const std::string& input = "/dev/null")
      : log_(std::move(log)) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, input.c_str(), O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, log_.c_str(), O_WRONLY | O_CREAT | O_APPEND,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  ~Process() { kill(SIGKILL); }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }

  // Sends `signal` and reaps the process; returns its exit code (-1 when killed by a signal).
  // After `timeout` without exiting it is killed.
  int kill(int signal, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
    if (exited_) return exit_code_;
    ::kill(pid_, signal);
    if (auto code = wait_for(timeout)) return *code;
    ::kill(pid_, SIGKILL);
    return *wait_for(std::chrono::hours(1));
  }

  // The exit code once it has exited within `timeout`, else nothing (-1 = killed by a signal).
  std::optional<int> wait_for(std::chrono::milliseconds timeout) {
    if (exited_) return exit_code_;
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return exit_code_;
      }
      if (std::chrono::steady_clock::now() >= until) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  std::string log() const {
    std::ifstream in(log_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  // Waits (bounded) until the log matches `pattern`; returns the first capture group.
  std::optional<std::string> wait_for_log(const std::string& pattern,
                                          std::chrono::milliseconds timeout) {
    const std::regex re(pattern);
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      std::smatch match;
      const std::string text = log();
      if (std::regex_search(text, match, re)) return match.size() > 1 ? match[1].str() : "";
      if (wait_for(std::chrono::milliseconds(0))) return std::nullopt;  // died
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return std::nullopt;
  }

 private:
  pid_t pid_ = -1;
  std::string log_;
  bool exited_ = false;
  int exit_code_ = -1;
};

// Polls `done` every 50 ms for at most `timeout`; true once it held.
template <class Predicate>
bool eventually(Predicate done, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return done();
}

}  // namespace primlabel::test
