#pragma once
// Records the largest single allocation of the test executable that links allocation_guard.cpp
// (it replaces the global operator new), so tests can prove that absurd header values are
// rejected before anything of that size is allocated.

#include <cstddef>

namespace primlabel::test {

void reset_largest_allocation();
std::size_t largest_allocation();

}  // namespace primlabel::test
