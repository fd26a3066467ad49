#pragma once
// Cooperative cancellation of long computations (normals, descriptors, inference). A caller that
// may give up (e.g. a service whose client disconnected) passes a std::stop_token; the per-point
// loops skip their remaining blocks once it is stopped and the function then throws Cancelled.
// A default-constructed token never stops and costs one branch per block.

#include <stdexcept>
#include <stop_token>
#include <string>

namespace primlabel {

class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws Cancelled("<what> cancelled") when `stop` has been requested.
inline void throw_if_stopped(const std::stop_token& stop, const char* what) {
  if (stop.stop_requested()) throw Cancelled(std::string(what) + " cancelled");
}

}  // namespace primlabel
