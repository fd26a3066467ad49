#pragma once
// New scan files in a directory, via inotify: a file counts once it is complete, i.e. closed
// after writing or renamed into the directory (the usual temp-file-then-rename). Hidden files
// (".name") and other extensions than .pcd / .ply are ignored.

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace primlabel::client::upload {

class DirectoryWatch {
 public:
  // Throws std::runtime_error naming the directory when it cannot be watched.
  explicit DirectoryWatch(const std::filesystem::path& dir);
  ~DirectoryWatch();
  DirectoryWatch(const DirectoryWatch&) = delete;
  DirectoryWatch& operator=(const DirectoryWatch&) = delete;

  // The scan files already there (call once, after construction, so none is missed).
  std::vector<std::filesystem::path> existing() const;
  // Files completed since the last call, waiting up to `timeout` for the first one.
  std::vector<std::filesystem::path> next(std::chrono::milliseconds timeout);

  static bool is_scan_name(const std::filesystem::path& path);

 private:
  std::filesystem::path dir_;
  int fd_ = -1;
};

}  // namespace primlabel::client::upload
