// The scan uploader: spool durability (crash leftovers, restart, corrupt entries), the spool-full
// policy, full disks (a small tmpfs when running as root), stdin framing, exactly-once outputs,
// retries, and the tool's exit codes, against the fake server.

#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "common/labeled_output.hpp"
#include "fake_labeler.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "process.hpp"
#include "small_filesystem.hpp"
#include "test_util.hpp"
#include "upload/framing.hpp"
#include "upload/spool.hpp"
#include "upload/uploader.hpp"

namespace primlabel {
namespace {

namespace fs = std::filesystem;
using client::upload::Spool;
using client::upload::SpoolFull;
using client::upload::SpoolWriteFailed;
using client::upload::Uploader;
using test::FakeServer;
using test::SmallFilesystem;
using test::write_bytes;

// The bytes of a small PCD scan whose fake labels are (i + seed) % 4.
std::string scan_bytes(int seed, std::size_t n = 200) {
  test::TempDir dir;
  PointCloud cloud;
  cloud.resize_unorganized(n);
  for (std::size_t i = 0; i < n; ++i) cloud.xyz[i] = Vec3f(float((i + seed) % 4), 0.01f * i, 1);
  write_pcd(dir.file("s.pcd"), cloud, PcdEncoding::kBinary);
  std::ifstream in(dir.file("s.pcd"), std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// Spool entries are named by their content hash, which the spool checks when it reopens.
std::string id_of(std::string_view bytes) { return client::upload::scan_id(bytes); }

std::size_t files_in(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), {}));
}

// Labeled clouds in an output directory (not the .classes.json files beside them).
std::size_t clouds_in(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  std::size_t clouds = 0;
  for (const auto& entry : fs::directory_iterator(dir))
    clouds += !entry.path().filename().string().ends_with(".classes.json");
  return clouds;
}

client::ClientOptions fast_client(const std::string& address) {
  client::ClientOptions options;
  options.address = address;
  options.deadline = std::chrono::seconds(20);
  options.retry_attempts = 1;
  options.backoff.initial = std::chrono::milliseconds(5);
  return options;
}

client::upload::UploaderOptions uploader_options(const test::TempDir& dir) {
  client::upload::UploaderOptions options;
  options.spool_dir = dir.file("spool");
  options.output_dir = dir.file("out");
  options.backoff = {std::chrono::milliseconds(10), 2.0, std::chrono::milliseconds(50), 0.2};
  return options;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Flips one bit in the middle of a file, as a failing disk would.
void flip_a_bit(const fs::path& path) {
  std::string bytes = read_text(path);
  ASSERT_FALSE(bytes.empty());
  bytes[bytes.size() / 2] ^= 0x10;
  write_bytes(path.string(), bytes);
}

// Waits (30 s at most) until every queued scan is uploaded or failed; true when it is.
bool wait_idle(Uploader& uploader) {
  const std::atomic<bool> stop{false};
  return uploader.wait_idle(stop, std::chrono::steady_clock::now() + std::chrono::seconds(30));
}

// ---------------------------------------------------------------------------------------------
// Spool

TEST(UploadSpool, ScanIdIsAStableContentHash) {
  EXPECT_EQ(client::upload::scan_id("abc"), client::upload::scan_id("abc"));
  EXPECT_NE(client::upload::scan_id("abc"), client::upload::scan_id("abd"));
  EXPECT_EQ(client::upload::scan_id("abc"), "ba7816bf8f01cfea414140de5dae2223");  // SHA-256
}

TEST(UploadSpool, AcceptedScansSurviveAReopenInAcceptanceOrder) {
  test::TempDir dir;
  const std::string first = "second-but-first", second = "x";
  {
    Spool spool(dir.file("spool"), {});
    EXPECT_EQ(spool.accept(id_of(first), first, ".pcd"), Spool::Accepted::kNew);
    EXPECT_EQ(spool.accept(id_of(second), second, ".ply"), Spool::Accepted::kNew);
    EXPECT_EQ(spool.accept(id_of(second), second, ".ply"), Spool::Accepted::kAlreadyQueued);
    EXPECT_EQ(spool.bytes(), 17u);
  }
  Spool reopened(dir.file("spool"), {});
  const auto pending = reopened.pending();
  ASSERT_EQ(pending.size(), 2u);
  EXPECT_EQ(reopened.bytes(), 17u);
  EXPECT_TRUE(reopened.contains(id_of(second)));
  EXPECT_EQ(pending[1].path.extension(), ".ply");
  reopened.complete(id_of(first));
  EXPECT_FALSE(fs::exists(pending[0].path));
  EXPECT_EQ(Spool(dir.file("spool"), {}).size(), 1u);
}

TEST(UploadSpool, ACrashMidWriteLeavesOnlyATempFileThatTheNextStartRemoves) {
  test::TempDir dir;
  { Spool spool(dir.file("spool"), {}); }
  // What a crash between write and rename leaves: a partial file in tmp/, nothing in scans/.
  write_bytes(dir.file("spool/tmp/0123.pcd.77.0.part"), "VERSION 0.7\nFIELDS x");
  write_bytes(dir.file("spool/tmp/4567.pcd.77.1.part"), "");
  Spool spool(dir.file("spool"), {});
  EXPECT_EQ(spool.removed_temp_files(), 2u);
  EXPECT_EQ(spool.size(), 0u);
  EXPECT_EQ(files_in(dir.file("spool/tmp")), 0u);
}

TEST(UploadSpool, WhenFullNewScansAreRefusedAndAcceptedOnesKept) {
  test::TempDir dir;
  Spool spool(dir.file("spool"), {/*max_bytes=*/100, /*max_scans=*/2});
  const std::string a(60, 'a'), b(41, 'b'), c(40, 'c'), d = "d";
  spool.accept(id_of(a), a, ".pcd");
  try {
    spool.accept(id_of(b), b, ".pcd");
    FAIL() << "accepted over the byte limit";
  } catch (const SpoolFull& e) {
    EXPECT_NE(std::string(e.what()).find("spool full"), std::string::npos);
  }
  spool.accept(id_of(c), c, ".pcd");                             // exactly fits
  EXPECT_THROW(spool.accept(id_of(""), "", ".pcd"), SpoolFull);  // over the scan count
  EXPECT_EQ(spool.size(), 2u);
  EXPECT_EQ(spool.bytes(), 100u);
  spool.complete(id_of(a));
  spool.accept(id_of(d), d, ".pcd");
  EXPECT_EQ(Spool(dir.file("spool"), {}).bytes(), 41u);  // what was accepted is on disk
}

TEST(UploadSpool, FailedScansMoveAsideWithTheirReason) {
  test::TempDir dir;
  Spool spool(dir.file("spool"), {});
  spool.accept("bad", "junk", ".pcd");
  spool.fail("bad", "INVALID_ARGUMENT: zero points");
  EXPECT_EQ(spool.size(), 0u);
  EXPECT_EQ(spool.bytes(), 0u);
  EXPECT_TRUE(fs::exists(dir.file("spool/failed/bad.pcd")));
  std::ifstream reason(dir.file("spool/failed/bad.error"));
  std::string line;
  std::getline(reason, line);
  EXPECT_EQ(line, "INVALID_ARGUMENT: zero points");
  EXPECT_EQ(Spool(dir.file("spool"), {}).size(), 0u);
}

TEST(UploadSpool, AScanThatWouldEatTheFreeSpaceMarginIsRefusedBeforeAnyWrite) {
  test::TempDir dir;
  client::upload::SpoolLimits limits;
  limits.min_free_bytes = std::numeric_limits<std::uint64_t>::max();  // no disk has that much
  Spool spool(dir.file("spool"), limits);
  try {
    spool.accept("a", "abc", ".pcd");
    FAIL() << "accepted without the free-space margin";
  } catch (const SpoolFull& e) {
    EXPECT_NE(std::string(e.what()).find("not enough free space"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(dir.file("spool")), std::string::npos) << e.what();
  }
  EXPECT_EQ(spool.size(), 0u);
  EXPECT_EQ(files_in(dir.file("spool/scans")), 0u);
  EXPECT_EQ(files_in(dir.file("spool/tmp")), 0u);
}

TEST(UploadSpool, AVanishedSpoolDirectoryRefusesTheScanNamingTheFile) {
  test::TempDir dir;
  Spool spool(dir.file("spool"), {});
  spool.accept("a", "first", ".pcd");
  fs::remove_all(dir.file("spool/scans"));  // the rename into scans/ fails
  try {
    spool.accept("b", "second", ".pcd");
    FAIL() << "accepted into a vanished directory";
  } catch (const SpoolWriteFailed& e) {
    EXPECT_NE(std::string(e.what()).find(dir.file("spool/scans")), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(files_in(dir.file("spool/tmp")), 0u);  // no partial entry
  EXPECT_FALSE(spool.contains("b"));
  fs::remove_all(dir.file("spool/tmp"));  // now the free-space check itself cannot look
  EXPECT_THROW(spool.accept("c", "third", ".pcd"), SpoolWriteFailed);
  EXPECT_EQ(spool.size(), 1u);
}

TEST(UploadSpool, ACorruptEntryGoesToFailedWithItsReasonAtTheNextStart) {
  test::TempDir dir;
  const std::string good = scan_bytes(50), bad = scan_bytes(51);
  const std::string good_id = client::upload::scan_id(good), bad_id = client::upload::scan_id(bad);
  client::upload::SpooledScan stored;
  {
    Spool spool(dir.file("spool"), {});
    spool.accept(bad_id, bad, ".pcd", &stored);
    spool.accept(good_id, good, ".pcd");
  }
  flip_a_bit(stored.path);
  Spool reopened(dir.file("spool"), {});
  ASSERT_EQ(reopened.size(), 1u);
  EXPECT_TRUE(reopened.contains(good_id));
  EXPECT_EQ(reopened.bytes(), good.size());  // the corrupt entry is out of the byte budget
  ASSERT_EQ(reopened.corrupt_entries().size(), 1u);
  EXPECT_EQ(reopened.corrupt_entries()[0].id, bad_id);
  EXPECT_TRUE(reopened.corrupt_entries()[0].moved);
  EXPECT_FALSE(fs::exists(stored.path));
  EXPECT_TRUE(fs::exists(dir.file("spool/failed/" + bad_id + ".pcd")));
  const std::string reason = read_text(dir.file("spool/failed/" + bad_id + ".error"));
  EXPECT_NE(reason.find("corrupt spool entry"), std::string::npos) << reason;
  EXPECT_NE(reason.find("not to its id " + bad_id), std::string::npos) << reason;
  EXPECT_EQ(Spool(dir.file("spool"), {}).corrupt_entries().size(), 0u);  // dealt with once
}

// ---------------------------------------------------------------------------------------------
// Framing

TEST(UploadFraming, FramesRoundTripAndBadStreamsAreErrors) {
  std::stringstream stream(client::upload::encode_frame("one") + client::upload::encode_frame("") +
                           client::upload::encode_frame(std::string(1000, 'z')));
  EXPECT_EQ(client::upload::read_frame(stream, 1 << 20), "one");
  EXPECT_EQ(client::upload::read_frame(stream, 1 << 20), "");
  EXPECT_EQ(client::upload::read_frame(stream, 1 << 20)->size(), 1000u);
  EXPECT_FALSE(client::upload::read_frame(stream, 1 << 20).has_value());

  std::stringstream garbage("VERSION 0.7 not framed");
  EXPECT_THROW(client::upload::read_frame(garbage, 1 << 20), client::upload::FrameError);
  std::string cut = client::upload::encode_frame("abcdef");
  cut.pop_back();
  std::stringstream truncated(cut);
  EXPECT_THROW(client::upload::read_frame(truncated, 1 << 20), client::upload::FrameError);
  std::stringstream big(client::upload::encode_frame(std::string(100, 'x')));
  EXPECT_THROW(client::upload::read_frame(big, 99), client::upload::FrameError);
  EXPECT_EQ(client::upload::scan_extension("ply\nformat ascii 1.0\n"), ".ply");
  EXPECT_EQ(client::upload::scan_extension("# .PCD v0.7\n"), ".pcd");
}

// ---------------------------------------------------------------------------------------------
// The uploader against the fake server

// A fresh spool and output folder, and a client of the fake server.
class UploaderWithFakeServer : public ::testing::Test {
 protected:
  // The uploader over `options`, started; it stops before the client and server go.
  Uploader& started_uploader(const client::upload::UploaderOptions& options) {
    uploader_.emplace(client, options);
    uploader_->start();
    return *uploader_;
  }
  Uploader& started_uploader() { return started_uploader(uploader_options(dir)); }

  FakeServer server;
  test::TempDir dir;
  client::Client client{fast_client(server.address())};

 private:
  std::optional<Uploader> uploader_;
};

TEST_F(UploaderWithFakeServer, LabelsEachScanOnceIntoItsOwnOutput) {
  Uploader& uploader = started_uploader();
  std::string id;
  EXPECT_EQ(uploader.submit(scan_bytes(1), ".pcd", &id), Uploader::Submitted::kAccepted);
  uploader.submit(scan_bytes(2), ".pcd");
  ASSERT_TRUE(wait_idle(uploader));
  const PointCloud out = read_cloud(uploader.output_path(id).string());
  ASSERT_EQ(out.labels.size(), 200u);
  for (std::size_t i = 0; i < 200; ++i) ASSERT_EQ(out.labels[i], (i + 1) % 4);
  EXPECT_EQ(clouds_in(dir.file("out")), 2u);
  EXPECT_EQ(files_in(dir.file("spool/scans")), 0u);
  // The same scan again: its output exists, it is not uploaded twice.
  EXPECT_EQ(uploader.submit(scan_bytes(1), ".pcd"), Uploader::Submitted::kAlreadyLabeled);
  uploader.stop();
  EXPECT_EQ(server.service.label_calls, 2);
  EXPECT_EQ(uploader.counters().uploaded, 2u);
  EXPECT_EQ(server.service.scan_ids.front().size(), 32u);  // the content hash travels as scan_id
}

TEST_F(UploaderWithFakeServer, RetriesWithBackoffWhileTheServerIsUnavailable) {
  server.service.unavailable_calls = 4;
  Uploader& uploader = started_uploader();
  std::string id;
  uploader.submit(scan_bytes(3), ".pcd", &id);
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(uploader.counters().retries, 4u);
  EXPECT_EQ(uploader.counters().uploaded, 1u);
  EXPECT_TRUE(fs::exists(uploader.output_path(id)));
  EXPECT_NE(uploader.status_line().find("retries 4"), std::string::npos) << uploader.status_line();
}

TEST_F(UploaderWithFakeServer, StartupResumesTheSpoolAndSkipsScansAlreadyWritten) {
  const auto options = uploader_options(dir);
  // A previous run accepted two scans and crashed after writing the first one's output.
  const std::string done_id = client::upload::scan_id(scan_bytes(4));
  const std::string todo_id = client::upload::scan_id(scan_bytes(5));
  {
    Spool spool(options.spool_dir, {});
    spool.accept(done_id, scan_bytes(4), ".pcd", nullptr, "scan_4");
    spool.accept(todo_id, scan_bytes(5), ".pcd", nullptr, "scan_5");
    fs::create_directories(options.output_dir);
    write_bytes((options.output_dir / client::upload::output_name(done_id, options.label, "scan_4"))
                    .string(),
                scan_bytes(4));
    write_bytes((options.output_dir / ("." + todo_id + ".pcd.tmp.1.0")).string(), "partial");
  }
  Uploader uploader(client, options);
  EXPECT_EQ(uploader.queued(), 1u);
  uploader.start();
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(server.service.label_calls, 1);
  EXPECT_EQ(uploader.counters().already_labeled, 1u);
  EXPECT_EQ(clouds_in(options.output_dir), 2u);  // the crash's temp file is gone
  EXPECT_EQ(files_in(options.spool_dir / "scans"), 0u);
  // The resumed scan's output is still named after its source file.
  EXPECT_TRUE(fs::exists(options.output_dir /
                         client::upload::output_name(todo_id, options.label, "scan_5")));
}

TEST_F(UploaderWithFakeServer, ARefusedScanMovesToFailedAndTheRestGoOn) {
  Uploader& uploader = started_uploader();
  std::string empty_id;
  uploader.submit(scan_bytes(6, 0), ".pcd", &empty_id);  // the server refuses zero points
  uploader.submit(scan_bytes(7), ".pcd");
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(uploader.counters().failed, 1u);
  EXPECT_EQ(uploader.counters().uploaded, 1u);
  EXPECT_TRUE(fs::exists(dir.file("spool/failed/" + empty_id + ".pcd")));
}

// A model the server does not serve (a typo) fails the scan for good with the server's reason,
// instead of retrying it forever and wedging the spool.
TEST_F(UploaderWithFakeServer, AModelTheServerDoesNotHaveFailsTheScanForGood) {
  client::upload::UploaderOptions options = uploader_options(dir);
  options.label.model = "faek";
  Uploader& uploader = started_uploader(options);
  std::string id;
  uploader.submit(scan_bytes(8), ".pcd", &id);
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(uploader.counters().failed, 1u);
  EXPECT_EQ(uploader.counters().retries, 0u);
  EXPECT_EQ(server.service.label_calls, 1);
  EXPECT_TRUE(fs::exists(dir.file("spool/failed/" + id + ".pcd")));
  EXPECT_NE(read_text(dir.file("spool/failed/" + id + ".error")).find("no model 'faek'"),
            std::string::npos);
}

TEST_F(UploaderWithFakeServer, ACorruptSpoolEntryIsNeverUploaded) {
  const auto options = uploader_options(dir);
  client::upload::SpooledScan stored;
  {
    Spool spool(options.spool_dir, {});
    spool.accept(client::upload::scan_id(scan_bytes(52)), scan_bytes(52), ".pcd", &stored);
    spool.accept(client::upload::scan_id(scan_bytes(53)), scan_bytes(53), ".pcd");
  }
  flip_a_bit(stored.path);
  Uploader uploader(client, options);
  EXPECT_EQ(uploader.queued(), 1u);
  uploader.start();
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(server.service.label_calls, 1);
  EXPECT_EQ(server.service.scan_ids, std::vector{client::upload::scan_id(scan_bytes(53))});
  EXPECT_EQ(uploader.counters().corrupt, 1u);
  EXPECT_EQ(clouds_in(options.output_dir), 1u);
}

// ---------------------------------------------------------------------------------------------
// Full disks: a 1 MiB tmpfs (root only; skipped otherwise)

// Distinct scans of 12,000 points: about 144 kB, so seven fill 1 MiB.
std::string big_scan(int seed) {
  test::TempDir dir;
  PointCloud cloud;
  cloud.resize_unorganized(12'000);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    cloud.xyz[i] = Vec3f(float(i % 4), 0.01f * i, 1 + 0.001f * seed);
  write_pcd(dir.file("s.pcd"), cloud, PcdEncoding::kBinary);
  return read_text(dir.file("s.pcd"));
}

TEST(UploadFullDisk, AWriteOutOfSpaceLeavesNoTempFileAndNamesTheReason) {
  test::TempDir dir;
  SmallFilesystem disk(dir.file("disk"), "size=1m");
  if (!disk.mounted()) GTEST_SKIP() << disk.why();
  fs::create_directories(disk.path("tmp"));
  ASSERT_GT(disk.fill("filler"), 0u);
  try {
    atomic_write_file(disk.path("scan.pcd"), big_scan(60), {.temp_dir = disk.path("tmp")});
    FAIL() << "wrote a scan to a full filesystem";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
  }
  EXPECT_EQ(files_in(disk.path("tmp")), 0u);
  EXPECT_FALSE(fs::exists(disk.path("scan.pcd")));
}

TEST(UploadFullDisk, ASpoolOutOfInodesRefusesTheScanAndKeepsWhatItHas) {
  test::TempDir dir;
  SmallFilesystem disk(dir.file("disk"), "size=1m,nr_inodes=32");
  if (!disk.mounted()) GTEST_SKIP() << disk.why();
  client::upload::SpoolLimits limits;
  limits.min_free_bytes = 0;
  Spool spool(disk.path("spool"), limits);
  spool.accept(id_of("first"), "first", ".pcd");
  ASSERT_GT(disk.fill_inodes("filler"), 0u);  // blocks are left, so only the write can see it
  try {
    spool.accept(id_of("second"), "second", ".pcd");
    FAIL() << "accepted without an inode";
  } catch (const SpoolWriteFailed& e) {
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(disk.path("spool/tmp").string()), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(files_in(disk.path("spool/tmp")), 0u);
  EXPECT_EQ(files_in(disk.path("spool/scans")), 1u);
  fs::remove_all(disk.path("filler"));
  EXPECT_EQ(spool.accept(id_of("second"), "second", ".pcd"), Spool::Accepted::kNew);
  EXPECT_EQ(Spool(disk.path("spool"), limits).size(), 2u);
}

TEST(UploadFullDisk, ASpoolThatFillsMidRunDrainsAfterSpaceReturns) {
  FakeServer server;
  test::TempDir dir;
  SmallFilesystem disk(dir.file("disk"), "size=1m");
  if (!disk.mounted()) GTEST_SKIP() << disk.why();
  auto options = uploader_options(dir);
  options.spool_dir = disk.path("spool");
  options.output_dir = disk.path("out");    // the same disk: an output needs space too
  options.limits.min_free_bytes = 200'000;  // what the margin is for: room for an output
  client::Client client(fast_client(server.address()));
  Uploader uploader(client, options);
  std::vector<std::string> accepted;
  std::string reason;
  int seed = 100;
  for (; seed < 120; ++seed) {
    std::string id;
    const auto result = uploader.submit(big_scan(seed), ".pcd", &id, &reason);
    if (result != Uploader::Submitted::kAccepted) {
      EXPECT_TRUE(result == Uploader::Submitted::kSpoolFull ||
                  result == Uploader::Submitted::kWriteFailed);
      break;
    }
    accepted.push_back(id);
  }
  ASSERT_GE(accepted.size(), 2u);
  ASSERT_LT(seed, 120) << "a 1 MiB spool took 20 scans of 144 kB";
  EXPECT_FALSE(reason.empty());
  EXPECT_EQ(files_in(disk.path("spool/tmp")), 0u);
  disk.fill("filler");  // not a block left for the outputs

  uploader.start();
  EXPECT_TRUE(
      test::eventually([&] { return uploader.counters().retries >= 2; }, std::chrono::seconds(20)));
  EXPECT_EQ(uploader.queued(), accepted.size());  // nothing accepted is lost
  EXPECT_EQ(files_in(disk.path("spool/scans")), accepted.size());

  fs::remove(disk.path("filler"));  // space returns
  ASSERT_TRUE(wait_idle(uploader));
  EXPECT_EQ(uploader.counters().uploaded, accepted.size());
  for (const std::string& id : accepted) EXPECT_TRUE(fs::exists(uploader.output_path(id))) << id;
  EXPECT_EQ(files_in(disk.path("spool/scans")), 0u);
  EXPECT_EQ(uploader.submit(big_scan(seed), ".pcd"), Uploader::Submitted::kAccepted);
  uploader.stop();
}

// ---------------------------------------------------------------------------------------------
// The tool

std::string upload_tool() { return test::binary("primlabel-upload"); }

TEST(UploadCli, SpoolFullRejectsWithExitFiveAndKeepsWhatItAccepted) {
  test::TempDir dir;
  std::string dead;
  { dead = FakeServer().address(); }
  std::vector<std::string> files;
  for (int i = 0; i < 4; ++i) {
    files.push_back(dir.file("s" + std::to_string(i) + ".pcd"));
    write_bytes(files.back(), scan_bytes(10 + i));
  }
  const std::string bytes = std::to_string(scan_bytes(10).size() * 2.5 / 1e6);
  const auto r = test::run_command(upload_tool() + " -q --retries 1 --timeout 0.5 --server " +
                                   dead + " --spool " + dir.file("spool") + " -o " +
                                   dir.file("out") + " --spool-max-mb " + bytes + " " + files[0] +
                                   " " + files[1] + " " + files[2] + " " + files[3]);
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("spool full"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("left in spool 2"), std::string::npos) << r.output;
  EXPECT_EQ(files_in(dir.file("spool/scans")), 2u);
}

TEST(UploadCli, AFullSpoolDiskRejectsWithExitFiveAndARestartDrainsBeforeTakingMore) {
  test::TempDir dir;
  SmallFilesystem disk(dir.file("disk"), "size=1m");
  if (!disk.mounted()) GTEST_SKIP() << disk.why();
  std::string files;
  for (int i = 0; i < 8; ++i) {
    write_bytes(dir.file("s" + std::to_string(i) + ".pcd"), big_scan(70 + i));
    files += " " + dir.file("s" + std::to_string(i) + ".pcd");
  }
  const std::string spool_out =
      " --spool " + disk.path("spool").string() + " -o " + dir.file("out") + files;
  std::string dead;
  { dead = FakeServer().address(); }
  // The default margin (16 MB) refuses everything on a 1 MiB disk, one line per scan.
  auto r = test::run_command(upload_tool() + " -q --retries 1 --timeout 0.5 --server " + dead +
                             spool_out);
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_NE(r.output.find("primlabel-upload: " + dir.file("s0.pcd") +
                          ": not enough free space on the spool's filesystem"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(files_in(disk.path("spool/scans")), 0u);

  r = test::run_command(upload_tool() + " -q --retries 1 --timeout 0.5 --spool-min-free-mb 0 " +
                        "--server " + dead + spool_out);
  EXPECT_EQ(r.exit_code, 5) << r.output;
  const std::size_t spooled = files_in(disk.path("spool/scans"));
  EXPECT_GE(spooled, 4u) << r.output;
  EXPECT_LT(spooled, 8u) << r.output;
  EXPECT_EQ(files_in(disk.path("spool/tmp")), 0u);
  disk.fill("filler");  // and the disk fills up completely before the restart

  // The restart uploads what is spooled first, which frees room for the rest.
  FakeServer server;
  r = test::run_command(upload_tool() + " -q --spool-min-free-mb 0 --server " + server.address() +
                        spool_out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(clouds_in(dir.file("out")), 8u) << r.output;
  EXPECT_EQ(server.service.label_calls, 8);
  EXPECT_EQ(files_in(disk.path("spool/scans")), 0u);
}

// The same through the tool: the run ends at once with exit 4 (scans moved to SPOOL/failed), the
// refusal naming the file.
TEST(UploadCli, AModelTypoExitsFourAtOnceNamingTheModel) {
  FakeServer server;
  test::TempDir dir;
  write_bytes(dir.file("s.pcd"), scan_bytes(9));
  const auto r = test::run_command("timeout 20 " + upload_tool() + " -q --model faek --server " +
                                   server.address() + " --spool " + dir.file("spool") + " -o " +
                                   dir.file("out") + " " + dir.file("s.pcd"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("no model 'faek'"), std::string::npos) << r.output;
  // Named by its file, not only by its hash.
  EXPECT_NE(r.output.find("primlabel-upload: " + dir.file("s.pcd") + " (id "), std::string::npos)
      << r.output;
  EXPECT_EQ(files_in(dir.file("spool/scans")), 0u);
  EXPECT_EQ(server.service.label_calls, 1);
}

// The output is named after its source, and its key covers the labeling options: the same scan
// with another --model or --probabilities is labeled anew into its own output, never answered
// with the old one; the same scan with the same options is not uploaded again.
TEST(UploadCli, OutputsAreNamedAfterTheirSourceAndKeyedByTheOptions) {
  FakeServer server;
  test::TempDir dir;
  write_bytes(dir.file("kitchen scan.pcd"), scan_bytes(40));
  const std::string common = upload_tool() + " -q --server " + server.address() + " --spool " +
                             dir.file("spool") + " -o " + dir.file("out") + " '" +
                             dir.file("kitchen scan.pcd") + "'";
  auto r = test::run_command(common);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accepted "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" -> " + dir.file("out/kitchen_scan.")), std::string::npos) << r.output;
  r = test::run_command(common);  // same scan, same options: its output exists
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("labeled "), std::string::npos) << r.output;
  EXPECT_EQ(server.service.label_calls, 1);
  r = test::run_command(common + " --probabilities");  // other options: labeled anew
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accepted "), std::string::npos) << r.output;
  EXPECT_EQ(server.service.label_calls, 2);
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.file("out")))
    if (entry.path().extension() == ".pcd") names.push_back(entry.path().filename().string());
  ASSERT_EQ(names.size(), 2u);
  // Each with the JSON that names its classes and fields (common/labeled_output.hpp).
  for (const std::string& name : names)
    EXPECT_TRUE(fs::exists(client::tools::classes_json_path(dir.file("out/" + name)))) << name;
  EXPECT_EQ(files_in(dir.file("out")), 4u);
  for (const std::string& name : names) EXPECT_EQ(name.rfind("kitchen_scan.", 0), 0u) << name;
  for (const std::string& name : names) {
    const PointCloud out = read_cloud(dir.file("out/" + name));
    EXPECT_EQ(out.find_field("prob_class_0") != nullptr,
              name == client::upload::output_name(client::upload::scan_id(scan_bytes(40)),
                                                  {.probabilities = true}, "kitchen scan"))
        << name;
  }
}

// A file of the caller's that does not parse is an input error (1, as documented), named in one
// line and never spooled or sent; it is not a scan the server refused (4).
TEST(UploadCli, AnUnreadableInputFileExitsOneWithOneLineAndIsNotSpooled) {
  FakeServer server;
  test::TempDir dir;
  write_bytes(dir.file("broken.pcd"), "VERSION 0.7\nFIELDS x y z\nnot a header\n");
  write_bytes(dir.file("good.pcd"), scan_bytes(61));
  const auto r =
      test::run_command("( " + upload_tool() + " -q --server " + server.address() + " --spool " +
                        dir.file("spool") + " -o " + dir.file("out") + " " +
                        dir.file("broken.pcd") + " " + dir.file("good.pcd") + " >/dev/null )");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(test::count_lines(r.output), 2) << r.output;  // the reason, and the summary
  EXPECT_NE(r.output.find("summary: accepted 1 new"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(dir.file("broken.pcd") + ": not spooled, unreadable"), std::string::npos)
      << r.output;
  EXPECT_EQ(server.service.label_calls, 1);  // the good file only
  EXPECT_EQ(clouds_in(dir.file("out")), 1u);
  EXPECT_EQ(files_in(dir.file("spool/failed")), 0u);
}

// A cloud with no finite point has nothing to label: the same input error, saying why.
TEST(UploadCli, ACloudWithNoFinitePointExitsOneAndIsNotSpooled) {
  FakeServer server;
  test::TempDir dir;
  write_cloud(dir.file("blind.pcd"), test::nan_cloud(40));
  write_bytes(dir.file("good.pcd"), scan_bytes(63));
  const auto r =
      test::run_command("( " + upload_tool() + " -q --server " + server.address() + " --spool " +
                        dir.file("spool") + " -o " + dir.file("out") + " " + dir.file("blind.pcd") +
                        " " + dir.file("good.pcd") + " >/dev/null )");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("blind.pcd: not spooled, unreadable: no point has finite coordinates "
                          "(40 points)"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(server.service.label_calls, 1);  // the good file only
  EXPECT_EQ(clouds_in(dir.file("out")), 1u);
}

TEST(UploadCli, TheServerComesFromPrimlabelServerWhenNoFlagGivesIt) {
  FakeServer server;
  test::TempDir dir;
  write_bytes(dir.file("a.pcd"), scan_bytes(62));
  const auto r = test::run_command("PRIMLABEL_SERVER=" + server.address() + " " + upload_tool() +
                                   " -q --spool " + dir.file("spool") + " -o " + dir.file("out") +
                                   " " + dir.file("a.pcd"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(server.service.label_calls, 1);
}

TEST(UploadCli, ACorruptSpoolEntryIsReportedAndExitsFour) {
  FakeServer server;
  test::TempDir dir;
  client::upload::SpooledScan stored;
  const std::string id = client::upload::scan_id(scan_bytes(54));
  {
    Spool spool(dir.file("spool"), {});
    spool.accept(id, scan_bytes(54), ".pcd", &stored);
  }
  flip_a_bit(stored.path);
  const auto r = test::run_command(upload_tool() + " -q --server " + server.address() +
                                   " --spool " + dir.file("spool") + " -o " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find(stored.path.string() + ": corrupt spool entry"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("corrupt 1"), std::string::npos) << r.output;
  EXPECT_EQ(server.service.label_calls, 0);
  EXPECT_EQ(clouds_in(dir.file("out")), 0u);
}

TEST(UploadCli, TimeoutWithTheServerAwayExitsThreeThenALaterRunDrainsTheSpool) {
  test::TempDir dir;
  write_bytes(dir.file("a.pcd"), scan_bytes(20));
  const std::string spool_out = " --spool " + dir.file("spool") + " -o " + dir.file("out");
  std::string dead;
  { dead = FakeServer().address(); }
  auto r = test::run_command(upload_tool() + " --retries 1 --timeout 0.5 --server " + dead +
                             spool_out + " " + dir.file("a.pcd"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("accepted "), std::string::npos) << r.output;
  EXPECT_EQ(files_in(dir.file("spool/scans")), 1u);
  FakeServer server;
  r = test::run_command(upload_tool() + " --server " + server.address() + spool_out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("resuming 1 scans"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("uploaded 1 (200 points)"), std::string::npos) << r.output;
  EXPECT_EQ(clouds_in(dir.file("out")), 1u);
  EXPECT_EQ(files_in(dir.file("spool/scans")), 0u);
}

TEST(UploadCli, StdinFramesAreAcknowledgedAndLabeled) {
  FakeServer server;
  test::TempDir dir;
  for (int i = 0; i < 3; ++i) write_bytes(dir.file(std::to_string(i) + ".pcd"), scan_bytes(30 + i));
  const auto r =
      test::run_command(upload_tool() + " --frame " + dir.file("0.pcd") + " " + dir.file("1.pcd") +
                        " " + dir.file("2.pcd") + " " + dir.file("0.pcd") + " | " + upload_tool() +
                        " --stdin -q --server " + server.address() + " --spool " +
                        dir.file("spool") + " -o " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(clouds_in(dir.file("out")), 3u);
  EXPECT_NE(r.output.find("accepted " + client::upload::scan_id(scan_bytes(31)) + " stdin#1"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(server.service.label_calls, 3);  // the repeated frame is the same scan
  const auto garbage = test::run_command("echo nonsense | " + upload_tool() +
                                         " --stdin -q --server " + server.address() + " --spool " +
                                         dir.file("spool") + " -o " + dir.file("out"));
  EXPECT_EQ(garbage.exit_code, 1) << garbage.output;  // an input that cannot be read
}

TEST(UploadCli, WatchedDirectoryScansAreUploadedUntilASignal) {
  FakeServer server;
  test::TempDir dir;
  fs::create_directories(dir.file("in"));
  write_bytes(dir.file("in/early.pcd"), scan_bytes(40));
  test::Process uploader(
      {upload_tool(), "--server", server.address(), "--watch", dir.file("in"), "--spool",
       dir.file("spool"), "-o", dir.file("out"), "--status-interval", "0.2"},
      dir.file("upload.log"));
  // A writer that renames finished files into place, and one that writes in place.
  write_bytes(dir.file("in/.late.pcd.tmp"), scan_bytes(41));
  fs::rename(dir.file("in/.late.pcd.tmp"), dir.file("in/late.pcd"));
  write_bytes(dir.file("in/direct.pcd"), scan_bytes(42));
  write_bytes(dir.file("in/notes.txt"), "ignored");
  EXPECT_TRUE(
      test::eventually([&] { return clouds_in(dir.file("out")) == 3; }, std::chrono::seconds(30)))
      << uploader.log();
  EXPECT_TRUE(uploader.wait_for_log("status: queued 0", std::chrono::seconds(10)))
      << uploader.log();
  EXPECT_EQ(uploader.kill(SIGTERM), 0) << uploader.log();
  EXPECT_NE(uploader.log().find("uploaded 3"), std::string::npos) << uploader.log();
}

// Exit 0 promises every scan labeled: a signal that ends a run of files with scans still spooled
// (the server away) exits 6 and says how many wait for the next run.
TEST(UploadCli, ASignalWithScansStillSpooledExitsSixSayingHowMany) {
  test::TempDir dir;
  write_bytes(dir.file("a.pcd"), scan_bytes(50));
  write_bytes(dir.file("b.pcd"), scan_bytes(51));
  std::string dead;
  { dead = FakeServer().address(); }
  test::Process uploader(
      {upload_tool(), "--retries", "1", "--server", dead, "--spool", dir.file("spool"), "-o",
       dir.file("out"), "--status-interval", "0", dir.file("a.pcd"), dir.file("b.pcd")},
      dir.file("upload.log"));
  ASSERT_TRUE(uploader.wait_for_log("accepted [0-9a-f]+ .*b\\.pcd", std::chrono::seconds(20)))
      << uploader.log();
  EXPECT_EQ(uploader.kill(SIGTERM), 6) << uploader.log();
  EXPECT_NE(uploader.log().find("stopped by signal with 2 scans still spooled; they resume on the "
                                "next run"),
            std::string::npos)
      << uploader.log();
  EXPECT_EQ(files_in(dir.file("spool/scans")), 2u);
  // With nothing left to do a signal changes nothing: --watch still exits 0 (see below).
}

// A writer that closes a file between writes makes the watch read it half-written: that is no
// input error while the file is completed later (it is retried when it changes and labeled), and
// one only if it is still unreadable when the run ends.
TEST(UploadCli, AWatchedFileReadHalfWrittenIsRetriedOnceComplete) {
  FakeServer server;
  test::TempDir dir;
  fs::create_directories(dir.file("in"));
  test::Process uploader(
      {upload_tool(), "--server", server.address(), "--watch", dir.file("in"), "--spool",
       dir.file("spool"), "-o", dir.file("out"), "--status-interval", "0"},
      dir.file("upload.log"));
  const std::string whole = scan_bytes(44);
  ASSERT_TRUE(
      test::eventually([&] { return fs::exists(dir.file("spool")); }, std::chrono::seconds(20)));
  write_bytes(dir.file("in/slow.pcd"), whole.substr(0, whole.size() / 2));
  ASSERT_TRUE(uploader.wait_for_log("slow\\.pcd: unreadable for now", std::chrono::seconds(20)))
      << uploader.log();
  write_bytes(dir.file("in/slow.pcd"), whole);  // the writer finishes
  EXPECT_TRUE(
      test::eventually([&] { return clouds_in(dir.file("out")) == 1; }, std::chrono::seconds(30)))
      << uploader.log();
  write_bytes(dir.file("in/broken.pcd"), "VERSION 0.7\nFIELDS x y z\nnot a header\n");
  ASSERT_TRUE(uploader.wait_for_log("broken\\.pcd: unreadable for now", std::chrono::seconds(20)))
      << uploader.log();
  fs::remove(dir.file("in/broken.pcd"));  // a temporary file that went away is nothing to report
  write_bytes(dir.file("in/bad.pcd"), "VERSION 0.7\nFIELDS x y z\nnot a header\n");
  ASSERT_TRUE(uploader.wait_for_log("bad\\.pcd: unreadable for now", std::chrono::seconds(20)))
      << uploader.log();
  // Still unreadable when the run ends: an input error, named once.
  EXPECT_EQ(uploader.kill(SIGTERM), 1) << uploader.log();
  const std::string log = uploader.log();
  EXPECT_NE(log.find("bad.pcd: not spooled, unreadable"), std::string::npos) << log;
  EXPECT_EQ(log.find("slow.pcd: not spooled"), std::string::npos) << log;
  EXPECT_EQ(log.find("broken.pcd: not spooled"), std::string::npos) << log;
  EXPECT_NE(log.find("uploaded 1"), std::string::npos) << log;
}

// Without a file left unreadable, the same half-written file ends the watch with 0.
TEST(UploadCli, AWatchWhoseHalfWrittenFileWasCompletedExitsZero) {
  FakeServer server;
  test::TempDir dir;
  fs::create_directories(dir.file("in"));
  test::Process uploader({upload_tool(), "-q", "--server", server.address(), "--watch",
                          dir.file("in"), "--spool", dir.file("spool"), "-o", dir.file("out")},
                         dir.file("upload.log"));
  const std::string whole = scan_bytes(45);
  ASSERT_TRUE(
      test::eventually([&] { return fs::exists(dir.file("spool")); }, std::chrono::seconds(20)));
  write_bytes(dir.file("in/slow.pcd"), whole.substr(0, whole.size() / 2));
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // read half-written (quietly)
  write_bytes(dir.file("in/slow.pcd"), whole);
  EXPECT_TRUE(
      test::eventually([&] { return clouds_in(dir.file("out")) == 1; }, std::chrono::seconds(30)))
      << uploader.log();
  EXPECT_EQ(uploader.kill(SIGTERM), 0) << uploader.log();
}

}  // namespace
}  // namespace primlabel
