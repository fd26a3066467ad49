#pragma once
// Progress reporting hook for long per-point loops. Called from one thread at a time with the
// number of points done so far; may be empty.

#include <cstddef>
#include <functional>

namespace primlabel {

using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

}  // namespace primlabel
