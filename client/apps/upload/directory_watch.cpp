#include "directory_watch.hpp"

#include <poll.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace primlabel::client::upload {

namespace fs = std::filesystem;

DirectoryWatch::DirectoryWatch(const fs::path& dir) : dir_(dir) {
  fd_ = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error(std::string("inotify: ") + std::strerror(errno));
  if (inotify_add_watch(fd_, dir.c_str(), IN_CLOSE_WRITE | IN_MOVED_TO) < 0) {
    const int saved = errno;
    ::close(fd_);
    throw std::runtime_error(dir.string() + ": cannot watch: " + std::strerror(saved));
  }
}

DirectoryWatch::~DirectoryWatch() {
  if (fd_ >= 0) ::close(fd_);
}

bool DirectoryWatch::is_scan_name(const fs::path& path) {
  const std::string name = path.filename().string();
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return !name.starts_with(".") && (ext == ".pcd" || ext == ".ply");
}

std::vector<fs::path> DirectoryWatch::existing() const {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir_))
    if (entry.is_regular_file() && is_scan_name(entry.path())) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<fs::path> DirectoryWatch::next(std::chrono::milliseconds timeout) {
  std::vector<fs::path> files;
  pollfd pfd{fd_, POLLIN, 0};
  if (::poll(&pfd, 1, static_cast<int>(timeout.count())) <= 0) return files;
  alignas(inotify_event) char buffer[64 * 1024];
  for (;;) {
    const ssize_t n = ::read(fd_, buffer, sizeof buffer);
    if (n <= 0) break;
    for (ssize_t at = 0; at < n;) {
      const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
      if (event->len > 0) {
        const fs::path path = dir_ / event->name;
        if (is_scan_name(path)) files.push_back(path);
      }
      at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
    }
  }
  return files;
}

}  // namespace primlabel::client::upload
