#pragma once
// The uploader's engine: takes scans into the spool, uploads them on worker threads, writes each
// scan's labels to <output>/<source name>.<key>.pcd (atomic rename, then fsync; output_name) and
// only then removes it from the spool. While the server is away (UNAVAILABLE, deadline,
// overload, ...) the workers pause with exponential backoff and resume when it answers again;
// nothing accepted is ever dropped. The key covers the scan's content and the labeling options
// (model, version, descriptors, ...), so a scan whose output for these options exists is never
// uploaded again, and the same scan with other options is labeled anew.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "primlabel/client/client.hpp"
#include "spool.hpp"

namespace primlabel::client::upload {

struct UploaderOptions {
  std::filesystem::path spool_dir;
  std::filesystem::path output_dir;
  SpoolLimits limits;
  LabelOptions label;  // model, descriptors, probabilities, ... for every scan
  BackoffPolicy backoff{std::chrono::milliseconds(500), 2.0, std::chrono::seconds(30), 0.2};
  int workers = 1;
};

struct UploadCounters {
  std::uint64_t accepted = 0;         // new scans taken into the spool
  std::uint64_t already_queued = 0;   // submitted again while in the spool
  std::uint64_t already_labeled = 0;  // submitted (or found in the spool) with output present
  std::uint64_t rejected_full = 0;    // refused: the spool (or its filesystem) was full
  std::uint64_t rejected_write = 0;   // refused: writing it into the spool failed
  std::uint64_t uploaded = 0;         // labeled and written
  std::uint64_t failed = 0;           // refused by the server for good (kept in spool/failed)
  std::uint64_t corrupt = 0;          // spool entries that did not match their id at start
  std::uint64_t retries = 0;          // uploads that will be tried again
  std::uint64_t points = 0;           // points labeled
};

// The labeling options that change an output, as one canonical line ("model=...;version=...;
// descriptors=0;..."): part of every output's key.
std::string options_fingerprint(const LabelOptions& options);

// "<source name>.<first 12 hex of the key>.pcd", or "<key>.pcd" without a name; the key is the
// SHA-256 of the content id and the options' fingerprint.
std::string output_name(const std::string& content_id, const LabelOptions& options,
                        const std::string& source_name);

class Uploader {
 public:
  // Opens the spool (recovering from a crash, setting corrupt entries aside) and queues what it
  // holds. Throws std::runtime_error when the spool or output directory cannot be used.
  Uploader(Client& client, UploaderOptions options);
  ~Uploader();  // stop()

  enum class Submitted { kAccepted, kAlreadyQueued, kAlreadyLabeled, kSpoolFull, kWriteFailed };
  // Takes one scan (its file bytes). Thread-safe. A scan the spool cannot take (full, or its
  // write failed) is not accepted and `reason` says why; nothing of it stays in the spool.
  // `source` (a file name, "stdin#3") names the scan in later messages about it, and a file's
  // stem names its output (source_name; empty: the output is named by its key alone).
  Submitted submit(std::string_view bytes, const std::string& ext, std::string* id = nullptr,
                   std::string* reason = nullptr, const std::string& source = {},
                   const std::string& source_name = {});

  void start();  // the worker threads
  // Blocks until every queued scan is uploaded or failed, `stop` becomes true, or `until` passes.
  // True when idle.
  bool wait_idle(const std::atomic<bool>& stop,
                 std::optional<std::chrono::steady_clock::time_point> until);
  void stop();  // cancels uploads in flight (their scans stay spooled) and joins the workers

  UploadCounters counters() const;
  std::size_t queued() const;  // in the spool, not yet uploaded (includes those in flight)
  bool server_down() const { return server_down_; }
  // Entries found corrupt at start (already moved to spool/failed), for the operator's log.
  const std::vector<CorruptEntry>& corrupt_entries() const { return spool_.corrupt_entries(); }
  // "queued 3, in flight 1, uploaded 10, failed 0, rejected 0, retries 2, spool 1.2/1024.0 MB,
  // server up"
  std::string status_line() const;
  // Where the labels of the scan with content id `id` from a source named `source_name` go.
  std::filesystem::path output_path(const std::string& id,
                                    const std::string& source_name = {}) const;

 private:
  void work();
  // Uploads one scan; returns false when it should be tried again later.
  bool upload(const SpooledScan& scan);
  void finish_from_output(const std::string& id);  // output exists: just leave the spool
  // "scan.pcd (id 1f2e...)" for a scan submitted in this run, else "spooled scan 1f2e...".
  std::string name_of(const std::string& id) const;

  Client& client_;
  UploaderOptions options_;
  Spool spool_;
  Backoff backoff_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<SpooledScan> queue_;
  std::size_t in_flight_ = 0;
  UploadCounters counters_;
  std::list<CallHandle> calls_;                 // in flight, for stop()
  std::map<std::string, std::string> sources_;  // id -> source, for scans submitted this run
  std::chrono::steady_clock::time_point paused_until_{};
  std::atomic<bool> server_down_{false};
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace primlabel::client::upload
