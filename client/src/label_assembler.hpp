#pragma once
// Puts the LabelChunks of one answer back together in input order and checks that they cover
// every point exactly once, with arrays of consistent sizes. Any violation is a ProtocolError:
// a server bug or a corrupted answer, never silently patched over.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "primlabel/client/client.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::client {

class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class LabelAssembler {
 public:
  LabelAssembler(std::size_t points, bool want_descriptors, bool want_probabilities,
                 bool want_segments = false, bool want_objects = false);

  void add(const v1::LabelChunk& chunk);
  // Checks coverage and column counts against the summary and hands the result over.
  LabelResult finish(const v1::LabelSummary& summary);

  std::size_t covered() const { return covered_count_; }

 private:
  // Columns per point of an optional array in a chunk of `count` points; -1 when absent.
  static int columns(std::size_t bytes, std::uint32_t count, const char* what, std::uint64_t first);
  // One uint32 a point (segment or object ids) into `out`, sized on the first chunk carrying it.
  void add_ids(const std::string& bytes, std::uint32_t count, std::uint64_t first, bool wanted,
               const char* what, std::vector<std::uint32_t>& out);

  std::size_t points_;
  bool want_descriptors_;
  bool want_probabilities_;
  bool want_segments_;
  bool want_objects_;
  std::vector<char> covered_;
  std::size_t covered_count_ = 0;
  LabelResult result_;
  int probability_columns_ = -1;
};

}  // namespace primlabel::client
