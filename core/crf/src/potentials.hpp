#pragma once
// Log-potentials of a CrfModel on one graph (the scores of model.hpp), shared by inference and
// training. Float, row-major, computed in fixed-size blocks so the values never depend on the
// thread count.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stop_token>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/model.hpp"

namespace primlabel::crf::detail {

using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The score functions below check `stop` once per block of nodes (or edges), skip the remaining
// blocks once it is requested and then throw primlabel::Cancelled; an empty token never stops.

// ---- Padded layouts of the inference fast path ------------------------------------------------
// Rows of K classes are stored with a stride padded to a multiple of 4 floats, so the per-class
// loops run on whole SSE/AVX vectors; pad entries are 0 unless stated otherwise.
inline int padded_classes(int k_count) { return (k_count + 3) / 4 * 4; }

// A growable buffer of trivially constructible values that is never zero-filled: resizing to a
// size it already has is free, and fresh pages are first touched by the (parallel) code that
// writes them instead of by a serial fill.
template <typename T>
class ScratchBuffer {
 public:
  T* resize(std::size_t n) {
    if (n > capacity_) {
      data_.reset(new T[n]);  // default-initialised: no fill
      capacity_ = n;
    }
    size_ = n;
    return data_.get();
  }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  std::size_t size() const { return size_; }
  std::size_t bytes() const { return capacity_ * sizeof(T); }
  void release() {
    data_.reset();
    capacity_ = size_ = 0;
  }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
};

// Undirected edge numbering: edge e is owned by the slot p of its lower endpoint i (neighbors[p]
// > i), numbered in node order; edge_of[p] = edge_of[reverse[p]] = e. Returns num_edges().
std::size_t number_edges(const Graph& graph, int threads, ScratchBuffer<std::uint32_t>& edge_of,
                         ScratchBuffer<std::uint32_t>& block_first_edge,
                         const std::stop_token& stop = {});

// theta_i(k) for every node into `out` (num_nodes x padded K, pads 0; inactive rows 0).
void node_scores_padded(const CrfModel& model, std::span<const float> descriptors,
                        const Graph& graph, int threads, float* out,
                        const std::stop_token& stop = {});

// theta_ij(k, k) per undirected edge (numbered by number_edges) into `out` (num_edges x padded K,
// pads 0), or psi_ij(k) - 1 = exp(min(theta, 60)) - 1 when `potentials_minus_one`.
void edge_terms_padded(const CrfModel& model, std::span<const float> descriptors,
                       const Graph& graph, const std::uint32_t* block_first_edge, int threads,
                       bool potentials_minus_one, float* out, const std::stop_token& stop = {});

// Loopy BP's node potentials from node_scores_padded's rows: phi_i(k) = exp(theta_i(k) -
// max_k theta_i(k)) (max 1), pads 0.
void node_potentials_padded(const float* theta, std::size_t n, int k_count, int threads,
                            float* phi);

// Products of tiny values would otherwise run into subnormals, which are ~100x slower on x86;
// flushing them to zero changes nothing that matters next to a maximum of 1.
class FlushSubnormals {
 public:
  FlushSubnormals() {
#if defined(__SSE2__)
    saved_ = _mm_getcsr();
    _mm_setcsr(saved_ | 0x8040);  // FTZ | DAZ
#endif
  }
  ~FlushSubnormals() {
#if defined(__SSE2__)
    if (armed_) _mm_setcsr(saved_);
#endif
  }
  // Movable into a thread's scratch (parallel_for): only the last owner restores the mode.
  FlushSubnormals(FlushSubnormals&& other) noexcept
      : saved_(other.saved_), armed_(std::exchange(other.armed_, false)) {}
  FlushSubnormals(const FlushSubnormals&) = delete;
  FlushSubnormals& operator=(const FlushSubnormals&) = delete;
  FlushSubnormals& operator=(FlushSubnormals&&) = delete;

 private:
  unsigned saved_ = 0;
  bool armed_ = true;
};

// Threads worth starting for `nodes` nodes: small graphs run on one thread, since a parallel
// region per BP iteration costs more than it saves there (and stalls on a busy machine).
// Results never depend on the thread count, so this only changes speed.
int useful_threads(int requested, std::size_t nodes);

// Checks that descriptors are num_nodes x model.descriptor_dim; throws std::invalid_argument.
void check_shapes(const CrfModel& model, std::span<const float> descriptors, const Graph& graph);

}  // namespace primlabel::crf::detail
