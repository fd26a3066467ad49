#include "uploader.hpp"

#include <cstdio>
#include <future>

#include "common/labeled_output.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"

namespace primlabel::client::upload {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// Statuses that say "this scan will never be labeled": retrying cannot help. NOT_FOUND is a
// model or version the server does not serve (a typo in --model): the server loads its
// repository before it listens, so retrying would wedge the spool on it. Everything else
// (UNAVAILABLE, DEADLINE_EXCEEDED, RESOURCE_EXHAUSTED, a bad token an operator will fix, ...) is
// retried with backoff.
bool permanent(grpc::StatusCode code) {
  return code == grpc::StatusCode::INVALID_ARGUMENT || code == grpc::StatusCode::OUT_OF_RANGE ||
         code == grpc::StatusCode::UNIMPLEMENTED || code == grpc::StatusCode::NOT_FOUND;
}

// Temp files of output writes a crash interrupted (core's atomic_write_file).
void remove_output_temp_files(const fs::path& dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_atomic_write_temp_name(name)) fs::remove(entry, ec);
  }
}

}  // namespace

std::string options_fingerprint(const LabelOptions& o) {
  std::string line = "model=" + o.model + ";version=" + o.model_version;
  line += ";descriptors=" + std::to_string(int(o.descriptors));
  line += ";probabilities=" + std::to_string(int(o.probabilities));
  line += ";tabletop=" + std::to_string(int(o.tabletop_only));
  line += ";every_point=" + std::to_string(int(o.every_point));
  char voxel[32];
  std::snprintf(voxel, sizeof voxel, ";voxel=%.9g", double(o.voxel_size));
  line += voxel;
  if (o.metres_per_unit != 1.0f) {  // only then: fingerprints of scans in metres stay as they were
    char units[32];
    std::snprintf(units, sizeof units, ";units=%.9g", double(o.metres_per_unit));
    line += units;
  }
  return line;
}

std::string output_name(const std::string& content_id, const LabelOptions& options,
                        const std::string& source_name) {
  const std::string key = scan_id(content_id + "\n" + options_fingerprint(options));
  const std::string name = safe_source_name(source_name);
  return name.empty() ? key + ".pcd" : name + "." + key.substr(0, 12) + ".pcd";
}

Uploader::Uploader(Client& client, UploaderOptions options)
    : client_(client),
      options_(std::move(options)),
      spool_(options_.spool_dir, options_.limits),
      backoff_(options_.backoff) {
  counters_.corrupt = spool_.corrupt_entries().size();
  std::error_code ec;
  fs::create_directories(options_.output_dir, ec);
  if (ec)
    throw std::runtime_error(options_.output_dir.string() + ": cannot create: " + ec.message());
  remove_output_temp_files(options_.output_dir);
  for (const SpooledScan& scan : spool_.pending()) {
    if (fs::exists(output_path(scan.id, scan.source_name))) {
      finish_from_output(scan.id);  // crashed after writing the output, before forgetting it
    } else {
      queue_.push_back(scan);
    }
  }
}

Uploader::~Uploader() { stop(); }

fs::path Uploader::output_path(const std::string& id, const std::string& source_name) const {
  return options_.output_dir / output_name(id, options_.label, source_name);
}

void Uploader::finish_from_output(const std::string& id) {
  spool_.complete(id);
  std::lock_guard lock(mutex_);
  ++counters_.already_labeled;
}

std::string Uploader::name_of(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const auto source = sources_.find(id);
  return source == sources_.end() ? "spooled scan " + id : source->second + " (id " + id + ")";
}

Uploader::Submitted Uploader::submit(std::string_view bytes, const std::string& ext,
                                     std::string* id_out, std::string* reason,
                                     const std::string& source, const std::string& source_name) {
  const std::string id = scan_id(bytes);
  if (id_out) *id_out = id;
  std::error_code ec;  // an unreadable output directory means "not labeled yet"
  if (fs::exists(output_path(id, source_name), ec)) {
    std::lock_guard lock(mutex_);
    ++counters_.already_labeled;
    return Submitted::kAlreadyLabeled;
  }
  Spool::Accepted accepted;
  SpooledScan stored;
  try {
    accepted = spool_.accept(id, bytes, ext, &stored, source_name);
  } catch (const SpoolFull& e) {
    if (reason) *reason = e.what();
    std::lock_guard lock(mutex_);
    ++counters_.rejected_full;
    return Submitted::kSpoolFull;
  } catch (const std::exception& e) {  // SpoolWriteFailed, or anything else the write threw
    if (reason) *reason = e.what();
    std::lock_guard lock(mutex_);
    ++counters_.rejected_write;
    return Submitted::kWriteFailed;
  }
  std::lock_guard lock(mutex_);
  // Named until it is labeled or failed (the first source, when the same bytes come twice).
  if (!source.empty()) sources_.emplace(id, source);
  if (accepted == Spool::Accepted::kAlreadyQueued) {
    ++counters_.already_queued;
    return Submitted::kAlreadyQueued;
  }
  queue_.push_back(stored);
  ++counters_.accepted;
  changed_.notify_all();
  return Submitted::kAccepted;
}

void Uploader::start() {
  for (int i = 0; i < std::max(1, options_.workers); ++i) workers_.emplace_back([this] { work(); });
}

void Uploader::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (auto& call : calls_) call.cancel();
    changed_.notify_all();
  }
  for (auto& worker : workers_) worker.join();
  workers_.clear();
}

void Uploader::work() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (queue_.empty()) {
      changed_.wait(lock);
      continue;
    }
    if (Clock::now() < paused_until_) {
      changed_.wait_until(lock, paused_until_);
      continue;
    }
    const SpooledScan scan = queue_.front();
    queue_.pop_front();
    ++in_flight_;
    lock.unlock();
    bool done = false;
    try {
      done = upload(scan);
    } catch (const std::exception& e) {  // the output or spool disk failed: try again later
      std::fprintf(stderr, "primlabel-upload: %s: %s\n", name_of(scan.id).c_str(), e.what());
    }
    lock.lock();
    --in_flight_;
    if (done) {
      backoff_.reset();
      server_down_ = false;
      sources_.erase(scan.id);  // labeled or failed: never named again
    } else {
      queue_.push_front(scan);
      ++counters_.retries;
      paused_until_ = Clock::now() + backoff_.next();
    }
    changed_.notify_all();
  }
}

bool Uploader::upload(const SpooledScan& scan) {
  const fs::path output = output_path(scan.id, scan.source_name);
  if (fs::exists(output)) {
    finish_from_output(scan.id);
    return true;
  }
  PointCloud cloud;
  try {
    cloud = read_cloud(scan.path.string());
  } catch (const std::exception& e) {
    spool_.fail(scan.id, e.what());
    std::fprintf(stderr, "primlabel-upload: %s: unreadable scan moved to %s: %s\n",
                 name_of(scan.id).c_str(), (spool_.dir() / "failed").c_str(), e.what());
    std::lock_guard lock(mutex_);
    ++counters_.failed;
    return true;
  }
  LabelOptions options = options_.label;
  options.scan_id = scan.id;
  std::promise<std::pair<CallStatus, LabelResult>> outcome;
  std::list<CallHandle>::iterator call;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return false;
    call = calls_.insert(calls_.end(),
                         client_.label_async(cloud, options, [&](CallStatus s, LabelResult r) {
                           outcome.set_value({std::move(s), std::move(r)});
                         }));
  }
  auto [status, result] = outcome.get_future().get();
  {
    std::lock_guard lock(mutex_);
    call->wait();
    calls_.erase(call);
  }
  if (!status.ok()) {
    if (status.code == grpc::StatusCode::CANCELLED) {
      std::lock_guard lock(mutex_);
      if (stopping_) return false;  // stop(): the scan stays spooled for the next run
    }
    if (permanent(status.code)) {
      spool_.fail(scan.id, status.message);
      std::fprintf(stderr, "primlabel-upload: %s: refused, moved to %s: %s\n",
                   name_of(scan.id).c_str(), (spool_.dir() / "failed").c_str(),
                   status.message.c_str());
      std::lock_guard lock(mutex_);
      ++counters_.failed;
      return true;
    }
    server_down_ = true;
    std::string hint;  // the client's deadline is the usual cause for a large scan
    if (status.code == grpc::StatusCode::DEADLINE_EXCEEDED)
      hint = " (--deadline is " +
             std::to_string(
                 std::chrono::duration_cast<std::chrono::seconds>(client_.options().deadline)
                     .count()) +
             " s; raise it for large scans)";
    std::fprintf(stderr, "primlabel-upload: %s: %s%s; will retry\n", name_of(scan.id).c_str(),
                 status.message.c_str(), hint.c_str());
    return false;
  }
  const std::size_t points = result.size();
  tools::write_labeled_cloud(output.string(), tools::labeled_cloud(std::move(cloud), result),
                             result);
  // write_pcd returns once the file and its directory entry are durable (atomic_write_file), so
  // the spool may forget the scan now.
  spool_.complete(scan.id);
  std::lock_guard lock(mutex_);
  ++counters_.uploaded;
  counters_.points += points;
  return true;
}

bool Uploader::wait_idle(const std::atomic<bool>& stop, std::optional<Clock::time_point> until) {
  std::unique_lock lock(mutex_);
  while (!(queue_.empty() && in_flight_ == 0)) {
    if (stop || (until && Clock::now() >= *until)) return false;
    changed_.wait_for(lock, std::chrono::milliseconds(100));
  }
  return true;
}

UploadCounters Uploader::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::size_t Uploader::queued() const {
  std::lock_guard lock(mutex_);
  return queue_.size() + in_flight_;
}

std::string Uploader::status_line() const {
  std::lock_guard lock(mutex_);
  char line[320];
  std::snprintf(line, sizeof line,
                "queued %zu, in flight %zu, uploaded %llu, failed %llu, rejected %llu, retries "
                "%llu, spool %.1f/%.1f MB, server %s",
                queue_.size() + in_flight_, in_flight_,
                static_cast<unsigned long long>(counters_.uploaded),
                static_cast<unsigned long long>(counters_.failed),
                static_cast<unsigned long long>(counters_.rejected_full + counters_.rejected_write),
                static_cast<unsigned long long>(counters_.retries), spool_.bytes() / 1e6,
                spool_.limits().max_bytes / 1e6, server_down_ ? "down" : "up");
  return line;
}

}  // namespace primlabel::client::upload
