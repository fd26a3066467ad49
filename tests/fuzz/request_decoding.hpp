#pragma once
// The server's request decoding without the transport, as server/service/src/labeling_session.cpp
// does it: check_header, then a ScanAssembler over every chunk, then finish(), stopping at the
// first refusal. This is the only file that knows what the assembler returns.

#include <optional>
#include <vector>

#include "primlabel/service/scan_assembler.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::fuzz {

inline bool refused(const std::optional<service::ServiceError>& error) { return error.has_value(); }

// The server's defaults (server_config.hpp: --max-points, --max-request-bytes).
inline service::ScanLimits server_default_limits() { return {10'000'000, 512ull << 20}; }

// Decodes one scan: `header`, then `chunks` in order. True when the server would label it.
inline bool decode_scan(const v1::ScanHeader& header,
                        const std::vector<const v1::PointChunk*>& chunks,
                        const service::ScanLimits& limits) {
  if (refused(service::check_header(header, limits))) return false;
  service::ScanAssembler assembler(header, limits);
  for (const v1::PointChunk* chunk : chunks)
    if (refused(assembler.add(*chunk))) return false;
  return !refused(assembler.finish());
}

}  // namespace primlabel::fuzz
