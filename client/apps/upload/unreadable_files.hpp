#pragma once
// Watched files that could not be read or parsed, with their size and modification time then: a
// file closed between writes (a writer that appends in several opens, a copy in chunks) is read
// half-written, and is retried once it changes rather than counted as a bad input.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace primlabel::client::upload {

class UnreadableFiles {
 public:
  // Records `path` as unreadable for `reason` as it is now; true when it was not recorded yet.
  bool note(const std::filesystem::path& path, const std::string& reason);
  void forget(const std::filesystem::path& path);
  // The recorded files whose size or modification time changed since (vanished ones are
  // forgotten: a temporary file that was renamed or removed is nothing to report).
  std::vector<std::filesystem::path> changed();
  // Each file still recorded, with its reason, by path.
  std::vector<std::pair<std::filesystem::path, std::string>> remaining() const;

 private:
  struct Seen {
    std::uintmax_t size = 0;
    std::filesystem::file_time_type modified;
    std::string reason;
  };
  std::map<std::filesystem::path, Seen> files_;
};

}  // namespace primlabel::client::upload
