#include "unreadable_files.hpp"

namespace primlabel::client::upload {

namespace fs = std::filesystem;

bool UnreadableFiles::note(const fs::path& path, const std::string& reason) {
  std::error_code ec;
  Seen seen;
  seen.size = fs::file_size(path, ec);
  if (ec) seen.size = 0;
  seen.modified = fs::last_write_time(path, ec);
  seen.reason = reason;
  return files_.insert_or_assign(path, std::move(seen)).second;
}

void UnreadableFiles::forget(const fs::path& path) { files_.erase(path); }

std::vector<fs::path> UnreadableFiles::changed() {
  std::vector<fs::path> out;
  for (auto it = files_.begin(); it != files_.end();) {
    std::error_code size_error, time_error;
    const std::uintmax_t size = fs::file_size(it->first, size_error);
    const fs::file_time_type modified = fs::last_write_time(it->first, time_error);
    if (size_error || time_error) {
      it = files_.erase(it);
      continue;
    }
    if (size != it->second.size || modified != it->second.modified) out.push_back(it->first);
    ++it;
  }
  return out;
}

std::vector<std::pair<fs::path, std::string>> UnreadableFiles::remaining() const {
  std::vector<std::pair<fs::path, std::string>> out;
  for (const auto& [path, seen] : files_) out.emplace_back(path, seen.reason);
  return out;
}

}  // namespace primlabel::client::upload
