#include "spool.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <openssl/sha.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

#include "primlabel/geometry/atomic_file.hpp"

namespace primlabel::client::upload {

namespace fs = std::filesystem;

namespace {

constexpr const char* kScans = "scans";
constexpr const char* kTemp = "tmp";
constexpr const char* kFailed = "failed";

[[noreturn]] void fail_errno(const std::string& what, const fs::path& path) {
  throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

bool is_scan_file(const fs::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".pcd" || ext == ".ply";
}

std::string id_from_digest(const unsigned char* digest) {
  static const char* const kHex = "0123456789abcdef";
  std::string id;
  for (int i = 0; i < 16; ++i) {
    id.push_back(kHex[digest[i] >> 4]);
    id.push_back(kHex[digest[i] & 15]);
  }
  return id;
}

// The scan id of a file's content, read in blocks so a large entry costs no memory. Throws
// std::runtime_error naming the file when it cannot be read.
std::string scan_id_of_file(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open", path);
  struct Closer {
    int fd;
    EVP_MD_CTX* context;
    ~Closer() {
      ::close(fd);
      EVP_MD_CTX_free(context);
    }
  } closer{fd, EVP_MD_CTX_new()};
  if (!closer.context || EVP_DigestInit_ex(closer.context, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error(path.string() + ": cannot start SHA-256");
  std::vector<unsigned char> block(1 << 20);
  for (;;) {
    const ssize_t n = ::read(fd, block.data(), block.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail_errno("read failed", path);
    if (n == 0) break;
    EVP_DigestUpdate(closer.context, block.data(), static_cast<std::size_t>(n));
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(closer.context, digest, &length);
  return id_from_digest(digest);
}

}  // namespace

std::string safe_source_name(const std::string& stem) {
  std::string out;
  for (char c : stem) {
    if (out.size() == 80) break;
    const bool safe =
        std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_';
    out.push_back(safe ? c : '_');
  }
  return out;
}

std::string scan_id(std::string_view bytes) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), digest);
  return id_from_digest(digest);
}

Spool::Spool(fs::path dir, SpoolLimits limits) : dir_(std::move(dir)), limits_(limits) {
  std::error_code ec;
  for (const char* sub : {kScans, kTemp, kFailed}) {
    fs::create_directories(dir_ / sub, ec);
    if (ec) throw std::runtime_error((dir_ / sub).string() + ": cannot create: " + ec.message());
  }
  // Temp files are writes that never got acknowledged: nobody was told they were accepted.
  for (const auto& entry : fs::directory_iterator(dir_ / kTemp)) {
    fs::remove(entry.path(), ec);
    ++removed_temp_files_;
  }
  // Files are "<sequence>_<id>[_<source name>]<ext>": the sequence keeps the acceptance order
  // across restarts (modification times are too coarse to order scans accepted in the same
  // millisecond); ids have no '_'.
  std::vector<std::pair<std::uint64_t, SpooledScan>> found;
  for (const auto& entry : fs::directory_iterator(dir_ / kScans)) {
    if (!entry.is_regular_file() || !is_scan_file(entry.path())) continue;
    const std::string stem = entry.path().stem().string();
    const auto underscore = stem.find('_');
    if (underscore == std::string::npos) continue;  // not ours
    std::uint64_t sequence = 0;
    try {
      sequence = std::stoull(stem.substr(0, underscore));
    } catch (const std::exception&) {
      continue;
    }
    const std::string rest = stem.substr(underscore + 1);
    const auto name_start = rest.find('_');
    const std::string id = rest.substr(0, name_start);
    const std::string source_name =
        name_start == std::string::npos ? std::string() : rest.substr(name_start + 1);
    next_sequence_ = std::max(next_sequence_, sequence + 1);  // corrupt entries included
    // A bit flipped on disk would otherwise be labeled under the original scan's id.
    std::string reason;
    try {
      const std::string actual = scan_id_of_file(entry.path());
      if (actual != id)
        reason = "corrupt spool entry: its content hashes to " + actual + ", not to its id " + id;
    } catch (const std::exception& e) {
      reason = std::string("unreadable spool entry: ") + e.what();
    }
    if (!reason.empty()) {
      CorruptEntry corrupt{id, entry.path(), reason};
      try {
        move_to_failed(id, entry.path(), reason);
      } catch (const std::exception&) {
        corrupt.moved = false;  // left where it is, checked again at the next start
      }
      corrupt_.push_back(std::move(corrupt));
      continue;
    }
    found.push_back({sequence, {id, entry.path(), entry.file_size(), source_name}});
  }
  std::sort(found.begin(), found.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [sequence, scan] : found) {
    bytes_ += scan.bytes;
    scans_.push_back(std::move(scan));
  }
}

std::vector<SpooledScan>::const_iterator Spool::find(const std::string& id) const {
  return std::find_if(scans_.begin(), scans_.end(),
                      [&](const SpooledScan& s) { return s.id == id; });
}

Spool::Accepted Spool::accept(const std::string& id, std::string_view bytes, const std::string& ext,
                              SpooledScan* stored, const std::string& source_name) {
  std::lock_guard lock(mutex_);
  if (const auto it = find(id); it != scans_.end()) {
    if (stored) *stored = *it;
    return Accepted::kAlreadyQueued;
  }
  if (scans_.size() + 1 > limits_.max_scans || bytes_ + bytes.size() > limits_.max_bytes)
    throw SpoolFull("spool full (" + std::to_string(scans_.size()) + " scans, " +
                    std::to_string(bytes_) + " of " + std::to_string(limits_.max_bytes) +
                    " bytes): scan of " + std::to_string(bytes.size()) + " bytes not accepted");
  check_free_space(bytes.size());
  char sequence[24];
  std::snprintf(sequence, sizeof sequence, "%016llu_",
                static_cast<unsigned long long>(next_sequence_));
  const std::string name = safe_source_name(source_name);
  const fs::path target = dir_ / kScans / (sequence + id + (name.empty() ? "" : "_" + name) + ext);
  try {
    atomic_write_file(target, bytes, {.temp_dir = dir_ / kTemp});
  } catch (const std::exception& e) {
    // The temp file is gone; a renamed file whose directory fsync failed must go too, or the
    // next start would resume a scan nobody was told was accepted.
    std::error_code ec;
    fs::remove(target, ec);
    throw SpoolWriteFailed(std::string("cannot spool the scan: ") + e.what());
  }
  ++next_sequence_;
  scans_.push_back({id, target, bytes.size(), name});
  if (stored) *stored = scans_.back();
  bytes_ += bytes.size();
  return Accepted::kNew;
}

void Spool::check_free_space(std::uint64_t scan_bytes) const {
  const fs::path temp = dir_ / kTemp;
  struct statvfs info {};
  if (::statvfs(temp.c_str(), &info) != 0)
    throw SpoolWriteFailed("cannot spool the scan: " + temp.string() +
                           ": cannot check free space: " + std::strerror(errno));
  const std::uint64_t free_bytes = std::uint64_t{info.f_bavail} * info.f_frsize;
  // Saturating: a huge margin must refuse, not wrap around.
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  const std::uint64_t needed =
      scan_bytes > kMax - limits_.min_free_bytes ? kMax : scan_bytes + limits_.min_free_bytes;
  if (free_bytes < needed)
    throw SpoolFull("not enough free space on the spool's filesystem (" + dir_.string() + ": " +
                    std::to_string(free_bytes) + " bytes free; a scan of " +
                    std::to_string(scan_bytes) + " bytes needs " + std::to_string(needed) +
                    " with the margin of " + std::to_string(limits_.min_free_bytes) +
                    "): not accepted");
}

std::vector<SpooledScan> Spool::pending() const {
  std::lock_guard lock(mutex_);
  return scans_;
}

bool Spool::contains(const std::string& id) const {
  std::lock_guard lock(mutex_);
  return find(id) != scans_.end();
}

void Spool::complete(const std::string& id) {
  std::lock_guard lock(mutex_);
  const auto it = find(id);
  if (it == scans_.end()) return;
  std::error_code ec;
  fs::remove(it->path, ec);
  if (ec) throw std::runtime_error(it->path.string() + ": cannot remove: " + ec.message());
  fsync_path(dir_ / kScans);
  bytes_ -= it->bytes;
  scans_.erase(it);
}

void Spool::move_to_failed(const std::string& id, const fs::path& path, const std::string& reason) {
  const fs::path target = dir_ / kFailed / (id + path.extension().string());
  atomic_write_file(dir_ / kFailed / (id + ".error"), reason + "\n", {.temp_dir = dir_ / kTemp});
  if (::rename(path.c_str(), target.c_str()) != 0) fail_errno("cannot move", path);
  fsync_path(dir_ / kFailed);
  fsync_path(dir_ / kScans);
}

void Spool::fail(const std::string& id, const std::string& reason) {
  std::lock_guard lock(mutex_);
  const auto it = find(id);
  if (it == scans_.end()) return;
  move_to_failed(id, it->path, reason);
  bytes_ -= it->bytes;
  scans_.erase(it);
}

std::uint64_t Spool::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

std::size_t Spool::size() const {
  std::lock_guard lock(mutex_);
  return scans_.size();
}

}  // namespace primlabel::client::upload
