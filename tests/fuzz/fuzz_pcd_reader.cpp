// libFuzzer target: read_pcd() on arbitrary bytes. The contract: a cloud that satisfies the
// invariants, or an IoError; anything else (another exception, a sanitizer report, an allocation
// over libFuzzer's -malloc_limit_mb) is a finding.

#include <cstddef>
#include <cstdint>

#include "cloud_invariants.hpp"
#include "fuzz_file_input.hpp"
#include "primlabel/geometry/cloud_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = primlabel::fuzz::input_file(".pcd");
  primlabel::fuzz::write_input(path, data, size);
  try {
    primlabel::fuzz::check_cloud(primlabel::read_pcd(path));
  } catch (const primlabel::IoError&) {
    // A malformed file, reported as the reader promises.
  }
  return 0;
}
