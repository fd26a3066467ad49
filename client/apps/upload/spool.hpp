#pragma once
// The uploader's durable spool: every accepted scan lives in <dir>/scans/<seq>_<id>[_<name>].<ext>
// (name: its source file's stem, so that its output is named after it after a restart) until its
// labels are safely in the output directory. A scan is accepted only once its bytes are on disk:
// written to <dir>/tmp/, fsynced, renamed into scans/ and the directory fsynced, so a crash or
// power loss at any moment leaves either no trace of an unacknowledged scan (a leftover temp
// file, removed at the next start) or the whole scan.
//
// The spool is bounded (bytes and scans, and a free-space margin on its filesystem). When a new
// scan does not fit, accept() refuses it with SpoolFull; when its write fails (ENOSPC, EIO, a
// vanished directory) with SpoolWriteFailed, leaving no trace of it. Accepted scans are never
// dropped to make room.
//
// At start every entry is checked against its id (the content hash): a corrupt one goes to
// failed/ with its reason, exactly like a scan the server refused, and is never uploaded.

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

// The spool cannot take a scan; it is not accepted and nothing of it is left in the spool.
class SpoolRefusal : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Over the spool's limits, or too little free space on its filesystem.
class SpoolFull : public SpoolRefusal {
 public:
  using SpoolRefusal::SpoolRefusal;
};
// Writing the scan failed (the message names the file and the system's reason).
class SpoolWriteFailed : public SpoolRefusal {
 public:
  using SpoolRefusal::SpoolRefusal;
};

struct SpoolLimits {
  std::uint64_t max_bytes = 1ull << 30;
  std::uint64_t max_scans = 10'000;
  // Free space the spool's filesystem must keep after a new scan (statvfs, before writing), so
  // a full disk is refused up front rather than by a failing write.
  std::uint64_t min_free_bytes = 16'000'000;
};

// A spool entry whose content no longer matches its id, found (and moved to failed/) at start.
struct CorruptEntry {
  std::string id;
  std::filesystem::path path;  // where it was in scans/
  std::string reason;
  bool moved = true;  // false: the move to failed/ itself failed; it is still ignored
};

struct SpooledScan {
  std::string id;
  std::filesystem::path path;
  std::uint64_t bytes = 0;
  std::string source_name;  // the source file's stem, made safe (safe_source_name); may be empty
};

// A source file's stem as a spool and output file name part: letters, digits, '.', '-' and '_'
// kept, anything else '_', at most 80 characters; "" for none.
std::string safe_source_name(const std::string& stem);

class Spool {
 public:
  // Opens (creating) the spool at `dir`: removes temp files of writes a crash interrupted,
  // verifies the scans already accepted against their ids and indexes the sound ones. Throws
  // std::runtime_error naming the directory.
  Spool(std::filesystem::path dir, SpoolLimits limits);

  enum class Accepted { kNew, kAlreadyQueued };

  // Stores the scan durably under `id` (no '_' in it) with extension `ext` (".pcd" or ".ply")
  // and its source's name, and tells where (`stored`). Throws SpoolFull when it does not fit,
  // SpoolWriteFailed when the write fails.
  Accepted accept(const std::string& id, std::string_view bytes, const std::string& ext,
                  SpooledScan* stored = nullptr, const std::string& source_name = {});

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
  const std::vector<CorruptEntry>& corrupt_entries() const { return corrupt_; }

 private:
  std::vector<SpooledScan>::const_iterator find(const std::string& id) const;
  void check_free_space(std::uint64_t scan_bytes) const;
  // Moves a scan file to failed/ beside a ".error" file holding `reason`.
  void move_to_failed(const std::string& id, const std::filesystem::path& path,
                      const std::string& reason);

  std::filesystem::path dir_;
  SpoolLimits limits_;
  mutable std::mutex mutex_;
  std::vector<SpooledScan> scans_;  // acceptance order
  std::uint64_t bytes_ = 0;
  std::uint64_t next_sequence_ = 0;
  std::size_t removed_temp_files_ = 0;
  std::vector<CorruptEntry> corrupt_;
};

}  // namespace primlabel::client::upload
