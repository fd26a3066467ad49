#include "primlabel/geometry/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace primlabel {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kTempMarker = ".tmp.";

[[noreturn]] void fail(const fs::path& path, const std::string& step, int error) {
  throw AtomicWriteError(path.string() + ": " + step + ": " +
                         std::generic_category().message(error));
}

fs::path directory_of(const fs::path& path) {
  return path.has_parent_path() ? path.parent_path() : fs::path(".");
}

// An open temporary file that is unlinked unless committed: every early exit (an error, an
// exception from the caller's writer) leaves nothing behind.
class TempFile {
 public:
  TempFile(const fs::path& target, const AtomicWriteOptions& options) : target_(target) {
    const std::string file_name = target.filename().string();
    if (file_name.empty() || file_name == "." || file_name == "..")
      throw AtomicWriteError(target.string() + ": cannot write: the path names no file");
    const fs::path directory = options.temp_dir.empty() ? directory_of(target) : options.temp_dir;
    // pid + a process-wide counter, created with O_EXCL: two writers (threads or processes) never
    // share a temporary file, and a leftover of a crashed process is never reused.
    static std::atomic<unsigned long long> sequence{0};
    for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
      path_ = directory / ("." + file_name + std::string(kTempMarker) + std::to_string(::getpid()) +
                           "." + std::to_string(sequence.fetch_add(1)));
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ < 0 && errno != EEXIST) break;
    }
    if (fd_ < 0) fail(target, "cannot create a temporary file in " + directory.string(), errno);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(path_.c_str());
  }

  int fd() const { return fd_; }
  // The stream now owns the descriptor (fclose closes it).
  void release_fd() { fd_ = -1; }

  // Syncs and closes the file (unless a stream closed it), renames it over the target and syncs
  // the target's directory.
  void commit() {
    if (fd_ >= 0) {
      if (::fsync(fd_) != 0) fail(target_, "fsync failed", errno);
      const int fd = fd_;
      fd_ = -1;
      if (::close(fd) != 0) fail(target_, "close failed", errno);
    }
    if (::rename(path_.c_str(), target_.c_str()) != 0)
      fail(target_, "cannot rename " + path_.filename().string() + " into place", errno);
    committed_ = true;
    const fs::path directory = directory_of(target_);
    try {
      fsync_path(directory);
    } catch (const AtomicWriteError& e) {
      throw AtomicWriteError(target_.string() + ": written, but the directory sync failed (" +
                             e.what() + ")");
    }
  }

 private:
  fs::path target_;
  fs::path path_;
  int fd_ = -1;
  bool committed_ = false;
};

}  // namespace

void atomic_write_file(const fs::path& path, std::string_view bytes,
                       const AtomicWriteOptions& options) {
  TempFile temp(path, options);
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t put = ::write(temp.fd(), bytes.data() + written, bytes.size() - written);
    if (put < 0 && errno == EINTR) continue;
    if (put <= 0) fail(path, "write failed", put < 0 ? errno : EIO);
    written += static_cast<std::size_t>(put);
  }
  temp.commit();
}

void atomic_write_file(const fs::path& path, const std::function<void(std::FILE*)>& write,
                       const AtomicWriteOptions& options) {
  TempFile temp(path, options);
  std::FILE* file = ::fdopen(temp.fd(), "wb");
  if (!file) fail(path, "cannot open a stream on the temporary file", errno);
  temp.release_fd();
  struct Closer {
    std::FILE*& file;
    ~Closer() {
      if (file) std::fclose(file);
    }
  } closer{file};
  write(file);
  if (std::fflush(file) != 0) fail(path, "write failed", errno);
  if (std::ferror(file)) fail(path, "write failed", errno ? errno : EIO);
  if (::fsync(::fileno(file)) != 0) fail(path, "fsync failed", errno);
  std::FILE* closing = file;
  file = nullptr;
  if (std::fclose(closing) != 0) fail(path, "close failed", errno);
  temp.commit();
}

bool is_atomic_write_temp_name(std::string_view file_name) {
  return file_name.starts_with('.') && file_name.find(kTempMarker) != std::string_view::npos;
}

void fsync_path(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open to sync", errno);
  const int rc = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (rc != 0) fail(path, "fsync failed", error);
}

}  // namespace primlabel
