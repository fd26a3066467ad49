// The allocation guard itself: the huge-header tests of test_pcd_io and test_ply_io prove nothing
// unless it sees large allocations. Both link the guard; this check runs once, in test_pcd_io.

#include <gtest/gtest.h>

#include <cstddef>
#include <vector>

#include "allocation_guard.hpp"

namespace primlabel::test {
namespace {

TEST(AllocationGuard, SeesLargeAllocations) {
  reset_largest_allocation();
  std::vector<char> big(std::size_t{2} << 20);
  EXPECT_GE(largest_allocation(), big.size());
}

}  // namespace
}  // namespace primlabel::test
