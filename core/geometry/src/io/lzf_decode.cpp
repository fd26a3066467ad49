#include "lzf_decode.hpp"

#include <lzf.h>

#include <cerrno>
#include <limits>

namespace primlabel::io_detail {

LzfDecoded lzf_decode(const unsigned char* in, std::size_t in_size, unsigned char* out,
                      std::size_t out_size) {
  constexpr std::size_t kMaxSize = std::numeric_limits<unsigned>::max();
  if (in_size > kMaxSize || out_size > kMaxSize) return {LzfStatus::kOutputOverflow, 0};
  if (in_size == 0) return {LzfStatus::kOk, 0};
  errno = 0;
  const unsigned produced = lzf_decompress(in, static_cast<unsigned>(in_size), out,
                                           static_cast<unsigned>(out_size));
  if (produced == 0)  // liblzf: E2BIG when the output is too small, EINVAL for a corrupt stream
    return {errno == E2BIG ? LzfStatus::kOutputOverflow : LzfStatus::kInvalid, 0};
  return {LzfStatus::kOk, produced};
}

}  // namespace primlabel::io_detail
