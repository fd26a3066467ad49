#pragma once
// The uploader's durable spool: every accepted scan lives in <dir>/scans/<seq>_<id>.<ext> until its
// labels are safely in the output directory. A scan is accepted only once its bytes are on disk:
// written to <dir>/tmp/, fsynced, renamed into scans/ and the directory fsynced, so a crash or
// power loss at any moment leaves either no trace of an unacknowledged scan (a leftover temp
// file, removed at the next start) or the whole scan.
//
// The spool is bounded (bytes and scans). When a new scan does not fit, accept() refuses it with
// SpoolFull; accepted scans are never dropped to make room.

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace primlabel::client::upload {

// A scan's stable id: the first 128 bits of the SHA-256 of its bytes, as 32 hex digits. The same
// scan gives the same id wherever and however often it is submitted.
std::string scan_id(std::string_view bytes);

class SpoolFull : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SpoolLimits {
  std::uint64_t max_bytes = 1ull << 30;
  std::uint64_t max_scans = 10'000;
};

struct SpooledScan {
  std::string id;
  std::filesystem::path path;
  std::uint64_t bytes = 0;
};

class Spool {
 public:
  // Opens (creating) the spool at `dir`: removes temp files of writes a crash interrupted and
  // indexes the scans already accepted. Throws std::runtime_error naming the directory.
  Spool(std::filesystem::path dir, SpoolLimits limits);

  enum class Accepted { kNew, kAlreadyQueued };

  // Stores the scan durably under `id` with extension `ext` (".pcd" or ".ply") and tells where
  // (`stored`). Throws SpoolFull when it does not fit, std::runtime_error when the write fails.
  Accepted accept(const std::string& id, std::string_view bytes, const std::string& ext,
                  SpooledScan* stored = nullptr);

  // Scans waiting, oldest accepted first (as indexed at start, then in acceptance order).
  std::vector<SpooledScan> pending() const;
  bool contains(const std::string& id) const;

  // The scan's labels are durable elsewhere: forget it (remove the file, fsync the directory).
  void complete(const std::string& id);
  // The server refused the scan for good: move it to <dir>/failed/ with the reason beside it, out
  // of the queue and the byte budget, for an operator to look at.
  void fail(const std::string& id, const std::string& reason);

  std::uint64_t bytes() const;
  std::size_t size() const;
  const SpoolLimits& limits() const { return limits_; }
  const std::filesystem::path& dir() const { return dir_; }
  std::size_t removed_temp_files() const { return removed_temp_files_; }

 private:
  std::vector<SpooledScan>::const_iterator find(const std::string& id) const;

  std::filesystem::path dir_;
  SpoolLimits limits_;
  mutable std::mutex mutex_;
  std::vector<SpooledScan> scans_;  // acceptance order
  std::uint64_t bytes_ = 0;
  std::uint64_t next_sequence_ = 0;
  std::size_t removed_temp_files_ = 0;
};

// Durable-write helpers the uploader shares with its output writer.
void fsync_path(const std::filesystem::path& path);  // a file or a directory
// Writes `bytes` to `target` via a temp file in `temp_dir` (same filesystem), fsync and rename,
// then fsyncs target's directory.
void write_file_durably(const std::filesystem::path& target, std::string_view bytes,
                        const std::filesystem::path& temp_dir);

}  // namespace primlabel::client::upload
