// The one atomic writer: whole files or nothing, no temporary file left behind, durable names.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "primlabel/geometry/atomic_file.hpp"
#include "test_util.hpp"

namespace primlabel {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Every name in `dir` other than the ones given: leftovers of a write.
std::vector<std::string> other_files(const fs::path& dir, const std::vector<std::string>& known) {
  std::vector<std::string> others;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (std::find(known.begin(), known.end(), name) == known.end()) others.push_back(name);
  }
  return others;
}

// Content that tells which writer and which round wrote it and whether it is whole: a header
// line with the length, then that many bytes of one letter.
std::string content(char letter, std::size_t size) {
  const std::string body(size, letter);
  return std::to_string(size) + "\n" + body;
}
bool whole(const std::string& text) {
  const auto newline = text.find('\n');
  if (newline == std::string::npos) return false;
  const std::size_t size = std::stoul(text.substr(0, newline));
  const std::string body = text.substr(newline + 1);
  return body.size() == size &&
         body.find_first_not_of(body.empty() ? ' ' : body[0]) == std::string::npos;
}

TEST(AtomicFile, WritesAndReplacesWithNothingLeftBeside) {
  test::TempDir dir;
  const fs::path path = dir.file("out.bin");
  atomic_write_file(path, "first");
  EXPECT_EQ(read_text(path), "first");
  atomic_write_file(path, std::string("sec\0ond", 7));
  EXPECT_EQ(read_text(path), std::string("sec\0ond", 7));
  atomic_write_file(path, "");
  EXPECT_EQ(fs::file_size(path), 0u);
  EXPECT_TRUE(other_files(dir.file(""), {"out.bin"}).empty());
}

TEST(AtomicFile, TheStreamWriterReplacesTheFileToo) {
  test::TempDir dir;
  const fs::path path = dir.file("report.txt");
  atomic_write_file(path, [](std::FILE* file) {
    for (int i = 0; i < 1000; ++i) std::fprintf(file, "line %d\n", i);
  });
  const std::string text = read_text(path);
  EXPECT_EQ(text.substr(0, 7), "line 0\n");
  EXPECT_EQ(text.size(), 10 * 7u + 90 * 8u + 900 * 9u);
  EXPECT_TRUE(other_files(dir.file(""), {"report.txt"}).empty());
}

TEST(AtomicFile, NewFilesGetTheUsualPermissions) {
  test::TempDir dir;
  const mode_t old_mask = ::umask(022);
  atomic_write_file(dir.file("a.pcd"), "x");
  ::umask(old_mask);
  struct stat info {};
  ASSERT_EQ(::stat(dir.file("a.pcd").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0644u);  // not mkstemp's 0600: other users read our outputs
}

TEST(AtomicFile, AWriterThatThrowsLeavesTheOldFileAndNoTemporary) {
  test::TempDir dir;
  const fs::path path = dir.file("model.plm");
  atomic_write_file(path, "old model");
  EXPECT_THROW(atomic_write_file(path,
                                 [](std::FILE* file) {
                                   std::fputs("half of a new mod", file);
                                   std::fflush(file);
                                   throw std::runtime_error("the writer failed");
                                 }),
               std::runtime_error);
  EXPECT_EQ(read_text(path), "old model");
  EXPECT_TRUE(other_files(dir.file(""), {"model.plm"}).empty());
}

TEST(AtomicFile, AMissingDirectoryNamesThePathAndTheReason) {
  test::TempDir dir;
  const fs::path path = dir.file("no/such/dir/out.pcd");
  try {
    atomic_write_file(path, "x");
    FAIL() << "wrote into a missing directory";
  } catch (const AtomicWriteError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
}

TEST(AtomicFile, AFailedRenameLeavesTheTargetAndNoTemporary) {
  test::TempDir dir;
  // A non-empty directory cannot be renamed over: the failure comes after the data is written.
  const fs::path path = dir.file("busy");
  fs::create_directories(path / "inside");
  try {
    atomic_write_file(path, "x");
    FAIL() << "replaced a directory";
  } catch (const AtomicWriteError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot rename"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(path / "inside"));
  EXPECT_TRUE(other_files(dir.file(""), {"busy"}).empty());
}

TEST(AtomicFile, APathThatNamesNoFileIsRefused) {
  EXPECT_THROW(atomic_write_file("", "x"), AtomicWriteError);
  test::TempDir dir;
  EXPECT_THROW(atomic_write_file(dir.file(".."), "x"), AtomicWriteError);
}

TEST(AtomicFile, TemporariesGoWhereTheOptionsSay) {
  test::TempDir dir;
  fs::create_directories(dir.file("tmp"));
  fs::create_directories(dir.file("out"));
  atomic_write_file(dir.file("out/a.pcd"), "a", {.temp_dir = dir.file("tmp")});
  EXPECT_EQ(read_text(dir.file("out/a.pcd")), "a");
  EXPECT_TRUE(fs::is_empty(dir.file("tmp")));
  // A temp directory that is not there fails before anything is written.
  EXPECT_THROW(atomic_write_file(dir.file("out/b.pcd"), "b", {.temp_dir = dir.file("gone")}),
               AtomicWriteError);
  EXPECT_FALSE(fs::exists(dir.file("out/b.pcd")));
}

TEST(AtomicFile, TemporaryNamesAreRecognised) {
  EXPECT_TRUE(is_atomic_write_temp_name(".scan.pcd.tmp.123.4"));
  EXPECT_FALSE(is_atomic_write_temp_name("scan.pcd"));
  EXPECT_FALSE(is_atomic_write_temp_name(".hidden.pcd"));
}

// Threads in this process and forked processes replace one path over and over while a reader
// watches it: every read sees a whole file, and at the end one writer's last file is there and
// no temporary is left.
TEST(AtomicFile, ConcurrentWritersToOnePathEndWithOneWholeFile) {
  test::TempDir dir;
  const fs::path path = dir.file("shared.pcd");
  atomic_write_file(path, content('a', 10));
  constexpr int kRounds = 60;
  std::vector<pid_t> children;
  for (char letter : {'p', 'q'}) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      int status = 0;
      try {
        for (int i = 0; i < kRounds; ++i) atomic_write_file(path, content(letter, 1000 + 37 * i));
      } catch (...) {
        status = 1;
      }
      ::_exit(status);
    }
    children.push_back(pid);
  }
  std::atomic<bool> writing{true};
  std::atomic<int> torn{0}, failed{0};
  std::thread reader([&] {
    while (writing) {
      const std::string text = read_text(path);
      if (!whole(text)) ++torn;
    }
  });
  std::vector<std::thread> writers;
  for (char letter : {'x', 'y', 'z'})
    writers.emplace_back([&, letter] {
      for (int i = 0; i < kRounds; ++i) {
        try {
          atomic_write_file(path, content(letter, 5000 + 13 * i));
        } catch (...) {
          ++failed;
        }
      }
    });
  for (std::thread& writer : writers) writer.join();
  for (pid_t pid : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  writing = false;
  reader.join();
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(torn, 0);
  const std::string last = read_text(path);
  EXPECT_TRUE(whole(last));
  EXPECT_NE(std::string("pqxyz").find(last.back()), std::string::npos);
  EXPECT_TRUE(other_files(dir.file(""), {"shared.pcd"}).empty());
}

}  // namespace
}  // namespace primlabel
