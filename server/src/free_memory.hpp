#pragma once
// Gives the heap's free pages back to the system after a large request. glibc keeps freed
// memory of big requests in its arenas (RSS stayed at 350-550 MB after one 5M-point scan), so a
// container's memory limit would see an idle server as full.

#include <malloc.h>

#include <cstdint>

namespace primlabel::server {

// Requests below this many points free too little to be worth the trim (a few ms).
inline constexpr std::uint64_t kTrimAfterPoints = 100'000;

inline void return_free_memory(std::uint64_t request_points) {
  if (request_points >= kTrimAfterPoints) malloc_trim(0);
}

}  // namespace primlabel::server
