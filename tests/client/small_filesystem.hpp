#pragma once
// A small tmpfs for tests of full disks: mounted on a fresh directory (needs root, or
// CAP_SYS_ADMIN; otherwise mounted() is false and why() says so, for GTEST_SKIP), unmounted when
// it goes out of scope. fill() and fill_inodes() use up what is left of it.

#include <fcntl.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace primlabel::test {

class SmallFilesystem {
 public:
  // `options` as for mount -o, e.g. "size=1m" or "size=1m,nr_inodes=16".
  SmallFilesystem(std::filesystem::path dir, const std::string& options) : dir_(std::move(dir)) {
    std::filesystem::create_directories(dir_);
    if (::geteuid() != 0) {
      why_ = "not running as root: cannot mount a small tmpfs to fill";
      return;
    }
    if (::mount("tmpfs", dir_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
      why_ = std::string("cannot mount a tmpfs on ") + dir_.string() + ": " + std::strerror(errno);
      return;
    }
    mounted_ = true;
  }
  ~SmallFilesystem() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallFilesystem(const SmallFilesystem&) = delete;
  SmallFilesystem& operator=(const SmallFilesystem&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& why() const { return why_; }
  std::filesystem::path path(const std::string& name) const { return dir_ / name; }

  // Writes `name` until the filesystem has no block left; returns the bytes written.
  std::size_t fill(const std::string& name) const {
    const int fd = ::open(path(name).c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) return 0;
    const std::vector<char> block(4096, 'f');
    std::size_t written = 0;
    for (int i = 0; i < (1 << 20); ++i) {  // bounded: a 4 GiB filesystem at most
      const ssize_t n = ::write(fd, block.data(), block.size());
      if (n <= 0) break;
      written += static_cast<std::size_t>(n);
    }
    ::close(fd);
    return written;
  }

  // Creates empty files in `subdir` until no inode is left; returns how many.
  std::size_t fill_inodes(const std::string& subdir) const {
    std::filesystem::create_directories(path(subdir));
    std::size_t created = 0;
    for (; created < 100'000; ++created) {
      const std::string file = (path(subdir) / std::to_string(created)).string();
      const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd < 0) break;
      ::close(fd);
    }
    return created;
  }

 private:
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string why_;
};

}  // namespace primlabel::test
