// Eight pairs per step with AVX2 where the CPU has it, else four with SSE2 (baseline x86-64). Every
// lane performs the same IEEE operations in the same order as the scalar pair_features, so the
// features are bit-identical; lanes whose fast answer could differ from the exact one (near ties of
// the source choice, angles near a bin boundary, signed zeros) are recomputed by the scalar exact
// path. Without SSE2 the scalar path does all the work.

#include "pair_bins_batch.hpp"

#include <algorithm>

#include "pair_features_inline.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace primlabel::detail {

namespace {

void exact_bins(const Vec3f& p1, const Vec3f& n1, const PairTargets& t, std::size_t j, int bins,
                std::uint8_t* alpha, std::uint8_t* phi, std::uint8_t* theta) {
  std::uint8_t b[3];
  pair_bins_exact(p1, n1, Vec3f(t.x[j], t.y[j], t.z[j]), Vec3f(t.nx[j], t.ny[j], t.nz[j]), bins, b);
  alpha[j] = b[0], phi[j] = b[1], theta[j] = b[2];
}

// The bins of `lanes` pairs from j on: the fast path's, except the lanes set in `redo`, which
// the exact path recomputes; with one_sided, the lanes set in `redo | tie` are marked there.
// Shared by the SSE2 and AVX2 loops.
void store_lanes(int lanes, int redo, int tie, const int* alpha_bins, const int* phi_bins,
                 const int* theta_bins, const Vec3f& p1, const Vec3f& n1, const PairTargets& t,
                 std::size_t j, int bins, std::uint8_t* alpha, std::uint8_t* phi,
                 std::uint8_t* theta, std::uint8_t* one_sided) {
  if (one_sided)
    for (int lane = 0; lane < lanes; ++lane)
      one_sided[j + lane] = static_cast<std::uint8_t>(((redo | tie) >> lane) & 1);
  for (int lane = 0; lane < lanes; ++lane) {
    if (redo & (1 << lane)) {
      exact_bins(p1, n1, t, j + lane, bins, alpha, phi, theta);
      continue;
    }
    alpha[j + lane] = static_cast<std::uint8_t>(std::clamp(alpha_bins[lane], 0, bins - 1));
    phi[j + lane] = static_cast<std::uint8_t>(phi_bins[lane]);
    theta[j + lane] = static_cast<std::uint8_t>(theta_bins[lane]);
  }
}

#if defined(__SSE2__)

inline __m128 select(__m128 mask, __m128 if_true, __m128 if_false) {
  return _mm_or_ps(_mm_and_ps(mask, if_true), _mm_andnot_ps(mask, if_false));
}
// (a.x*b.x + a.z*b.z) + (a.y*b.y + 0), as dot4.
inline __m128 dot4(__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz) {
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(az, bz)),
                    _mm_add_ps(_mm_mul_ps(ay, by), _mm_setzero_ps()));
}
inline __m128 abs_ps(__m128 v) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), v); }

// floor(bins * ((c + 1.0) * 0.5)) in double, clamped: truncation equals floor after the clamp
// because only values below 0 differ and both clamp them to 0.
inline void cosine_bins(__m128 c, int bins, int out[4]) {
  const __m128d one = _mm_set1_pd(1.0), half = _mm_set1_pd(0.5), scale = _mm_set1_pd(bins);
  const __m128d lo = _mm_mul_pd(scale, _mm_mul_pd(_mm_add_pd(_mm_cvtps_pd(c), one), half));
  const __m128d hi =
      _mm_mul_pd(scale, _mm_mul_pd(_mm_add_pd(_mm_cvtps_pd(_mm_movehl_ps(c, c)), one), half));
  alignas(16) int tmp[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(tmp),
                  _mm_unpacklo_epi64(_mm_cvttpd_epi32(lo), _mm_cvttpd_epi32(hi)));
  for (int i = 0; i < 4; ++i) out[i] = std::clamp(tmp[i], 0, bins - 1);
}

#endif

#if defined(__x86_64__) && defined(__GNUC__)
#define PRIMLABEL_PAIR_BINS_AVX2 1

#define PRIMLABEL_AVX2 __attribute__((target("avx2"), always_inline)) inline
PRIMLABEL_AVX2 __m256 select8(__m256 mask, __m256 if_true, __m256 if_false) {
  return _mm256_or_ps(_mm256_and_ps(mask, if_true), _mm256_andnot_ps(mask, if_false));
}
PRIMLABEL_AVX2 __m256 dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
  return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(az, bz)),
                       _mm256_add_ps(_mm256_mul_ps(ay, by), _mm256_setzero_ps()));
}
PRIMLABEL_AVX2 __m256 abs8(__m256 v) { return _mm256_andnot_ps(_mm256_set1_ps(-0.0f), v); }
PRIMLABEL_AVX2 void cosine_bins8(__m256 c, int bins, int out[8]) {
  const __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5), scale = _mm256_set1_pd(bins);
  const __m256d lo = _mm256_mul_pd(
      scale, _mm256_mul_pd(_mm256_add_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(c)), one), half));
  const __m256d hi = _mm256_mul_pd(
      scale, _mm256_mul_pd(_mm256_add_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(c, 1)), one), half));
  alignas(32) int tmp[8];
  _mm_store_si128(reinterpret_cast<__m128i*>(tmp), _mm256_cvttpd_epi32(lo));
  _mm_store_si128(reinterpret_cast<__m128i*>(tmp + 4), _mm256_cvttpd_epi32(hi));
  for (int i = 0; i < 8; ++i) out[i] = std::clamp(tmp[i], 0, bins - 1);
}

// The same lane program as the SSE loop below, eight pairs a step; compiled for AVX2 only here
// and called only when the CPU has it (no FMA: the products and sums round as in the SSE and
// scalar paths). Returns how many pairs it handled (a multiple of 8).
__attribute__((target("avx2"))) std::size_t pair_bins_avx2(const Vec3f& p1, const Vec3f& n1,
                                                           const PairTargets& t, std::size_t count,
                                                           int bins, std::uint8_t* alpha,
                                                           std::uint8_t* phi, std::uint8_t* theta,
                                                           std::uint8_t* one_sided) {
  const __m256 sign = _mm256_set1_ps(-0.0f);
  const __m256 p1x = _mm256_set1_ps(p1.x()), p1y = _mm256_set1_ps(p1.y()),
               p1z = _mm256_set1_ps(p1.z());
  const __m256 n1x = _mm256_set1_ps(n1.x()), n1y = _mm256_set1_ps(n1.y()),
               n1z = _mm256_set1_ps(n1.z());
  const __m256 zero = _mm256_setzero_ps(), unit = _mm256_set1_ps(1.0f);
  const __m256 pi = _mm256_set1_ps(static_cast<float>(M_PI));
  const __m256 half_pi = _mm256_set1_ps(static_cast<float>(M_PI_2));
  const __m256 to_bins = _mm256_set1_ps(static_cast<float>(bins / (2.0 * M_PI)));
  std::size_t j = 0;
  for (; j + 8 <= count; j += 8) {
    const __m256 qx = _mm256_loadu_ps(&t.x[j]), qy = _mm256_loadu_ps(&t.y[j]),
                 qz = _mm256_loadu_ps(&t.z[j]);
    const __m256 m2x = _mm256_loadu_ps(&t.nx[j]), m2y = _mm256_loadu_ps(&t.ny[j]),
                 m2z = _mm256_loadu_ps(&t.nz[j]);
    __m256 dx = _mm256_sub_ps(qx, p1x), dy = _mm256_sub_ps(qy, p1y), dz = _mm256_sub_ps(qz, p1z);
    const __m256 dist = _mm256_sqrt_ps(dot8(dx, dy, dz, dx, dy, dz));
    __m256 exact = _mm256_cmp_ps(dist, zero, _CMP_EQ_OQ);
    const __m256 angle1 = _mm256_div_ps(dot8(n1x, n1y, n1z, dx, dy, dz), dist);
    const __m256 angle2 = _mm256_div_ps(dot8(m2x, m2y, m2z, dx, dy, dz), dist);

    const __m256 abs1 = abs8(angle1), abs2 = abs8(angle2);
    const __m256 swap = _mm256_cmp_ps(abs1, abs2, _CMP_LT_OS);
    const __m256 gap = abs8(_mm256_sub_ps(abs1, abs2));
    // Not clearly apart (or NaN): the reversed pair may choose the other source.
    const __m256 tie = _mm256_cmp_ps(gap, _mm256_set1_ps(2e-6f), _CMP_NGT_UQ);
    exact = _mm256_or_ps(exact, _mm256_and_ps(_mm256_cmp_ps(gap, _mm256_set1_ps(2e-6f), _CMP_LE_OS),
                                              _mm256_cmp_ps(abs1, abs2, _CMP_NEQ_UQ)));
    const __m256 ux = select8(swap, m2x, n1x), uy = select8(swap, m2y, n1y),
                 uz = select8(swap, m2z, n1z);
    const __m256 tx = select8(swap, n1x, m2x), ty = select8(swap, n1y, m2y),
                 tz = select8(swap, n1z, m2z);
    const __m256 flip = _mm256_and_ps(swap, sign);
    dx = _mm256_xor_ps(dx, flip), dy = _mm256_xor_ps(dy, flip), dz = _mm256_xor_ps(dz, flip);
    const __m256 theta_value = select8(swap, _mm256_xor_ps(angle2, sign), angle1);

    __m256 vx = _mm256_sub_ps(_mm256_mul_ps(dy, uz), _mm256_mul_ps(dz, uy));
    __m256 vy = _mm256_sub_ps(_mm256_mul_ps(dz, ux), _mm256_mul_ps(dx, uz));
    __m256 vz = _mm256_sub_ps(_mm256_mul_ps(dx, uy), _mm256_mul_ps(dy, ux));
    const __m256 v_norm = _mm256_sqrt_ps(dot8(vx, vy, vz, vx, vy, vz));
    exact = _mm256_or_ps(exact, _mm256_cmp_ps(v_norm, zero, _CMP_EQ_OQ));
    vx = _mm256_div_ps(vx, v_norm), vy = _mm256_div_ps(vy, v_norm), vz = _mm256_div_ps(vz, v_norm);
    const __m256 wx = _mm256_sub_ps(_mm256_mul_ps(uy, vz), _mm256_mul_ps(uz, vy));
    const __m256 wy = _mm256_sub_ps(_mm256_mul_ps(uz, vx), _mm256_mul_ps(ux, vz));
    const __m256 wz = _mm256_sub_ps(_mm256_mul_ps(ux, vy), _mm256_mul_ps(uy, vx));
    const __m256 phi_value = dot8(vx, vy, vz, tx, ty, tz);
    const __m256 y = dot8(wx, wy, wz, tx, ty, tz);
    const __m256 x = dot8(ux, uy, uz, tx, ty, tz);

    const __m256 ax = abs8(x), ay = abs8(y);
    const __m256 largest = _mm256_max_ps(ax, ay), smallest = _mm256_min_ps(ax, ay);
    const __m256 degenerate =
        _mm256_or_ps(_mm256_cmp_ps(largest, zero, _CMP_EQ_OQ), _mm256_cmp_ps(y, zero, _CMP_EQ_OQ));
    exact = _mm256_or_ps(exact, degenerate);
    const __m256 a = _mm256_div_ps(smallest, select8(degenerate, unit, largest));
    const __m256 a2 = _mm256_mul_ps(a, a);
    __m256 r = _mm256_set1_ps(-0.01172120f);
    r = _mm256_add_ps(_mm256_mul_ps(r, a2), _mm256_set1_ps(0.05265332f));
    r = _mm256_add_ps(_mm256_mul_ps(r, a2), _mm256_set1_ps(-0.11643287f));
    r = _mm256_add_ps(_mm256_mul_ps(r, a2), _mm256_set1_ps(0.19354346f));
    r = _mm256_add_ps(_mm256_mul_ps(r, a2), _mm256_set1_ps(-0.33262347f));
    r = _mm256_add_ps(_mm256_mul_ps(r, a2), _mm256_set1_ps(0.99997726f));
    r = _mm256_mul_ps(r, a);
    r = select8(_mm256_cmp_ps(ay, ax, _CMP_GT_OS), _mm256_sub_ps(half_pi, r), r);
    r = select8(_mm256_cmp_ps(x, zero, _CMP_LT_OS), _mm256_sub_ps(pi, r), r);
    r = _mm256_xor_ps(r, _mm256_and_ps(y, sign));
    const __m256 scaled = _mm256_mul_ps(_mm256_add_ps(r, pi), to_bins);
    const __m256i whole = _mm256_cvttps_epi32(scaled);
    const __m256 fraction = _mm256_sub_ps(scaled, _mm256_cvtepi32_ps(whole));
    exact = _mm256_or_ps(
        exact, _mm256_or_ps(_mm256_cmp_ps(fraction, _mm256_set1_ps(5e-4f), _CMP_LT_OS),
                            _mm256_cmp_ps(fraction, _mm256_set1_ps(1.0f - 5e-4f), _CMP_GT_OS)));

    alignas(32) int alpha_bins[8];
    int phi_bins[8], theta_bins[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(alpha_bins), whole);
    cosine_bins8(phi_value, bins, phi_bins);
    cosine_bins8(theta_value, bins, theta_bins);
    store_lanes(8, _mm256_movemask_ps(exact), _mm256_movemask_ps(tie), alpha_bins, phi_bins,
                theta_bins, p1, n1, t, j, bins, alpha, phi, theta, one_sided);
  }
  return j;
}

#undef PRIMLABEL_AVX2

bool cpu_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

}  // namespace

void pair_bins_exact(const Vec3f& p1, const Vec3f& n1, const Vec3f& p2, const Vec3f& n2, int bins,
                     std::uint8_t bins_out[3]) {
  PairFeatures f;
  pair_features(p1, n1, p2, n2, f);
  bins_out[0] = static_cast<std::uint8_t>(angle_bin(f.alpha, bins));
  bins_out[1] = static_cast<std::uint8_t>(cosine_bin(f.phi, bins));
  bins_out[2] = static_cast<std::uint8_t>(cosine_bin(f.theta, bins));
}

void pair_bins_batch(const Vec3f& p1, const Vec3f& n1, const PairTargets& t, std::size_t count,
                     int bins, std::uint8_t* alpha, std::uint8_t* phi, std::uint8_t* theta,
                     std::uint8_t* one_sided) {
  std::size_t j = 0;
#if defined(PRIMLABEL_PAIR_BINS_AVX2)
  if (cpu_has_avx2()) j = pair_bins_avx2(p1, n1, t, count, bins, alpha, phi, theta, one_sided);
#endif
#if defined(__SSE2__)
  const __m128 p1x = _mm_set1_ps(p1.x()), p1y = _mm_set1_ps(p1.y()), p1z = _mm_set1_ps(p1.z());
  const __m128 n1x = _mm_set1_ps(n1.x()), n1y = _mm_set1_ps(n1.y()), n1z = _mm_set1_ps(n1.z());
  const __m128 zero = _mm_setzero_ps(), sign = _mm_set1_ps(-0.0f);
  const __m128 pi = _mm_set1_ps(static_cast<float>(M_PI));
  const __m128 half_pi = _mm_set1_ps(static_cast<float>(M_PI_2));
  const __m128 to_bins = _mm_set1_ps(static_cast<float>(bins / (2.0 * M_PI)));
  for (; j + 4 <= count; j += 4) {
    const __m128 qx = _mm_loadu_ps(&t.x[j]), qy = _mm_loadu_ps(&t.y[j]), qz = _mm_loadu_ps(&t.z[j]);
    const __m128 m2x = _mm_loadu_ps(&t.nx[j]), m2y = _mm_loadu_ps(&t.ny[j]),
                 m2z = _mm_loadu_ps(&t.nz[j]);
    __m128 dx = _mm_sub_ps(qx, p1x), dy = _mm_sub_ps(qy, p1y), dz = _mm_sub_ps(qz, p1z);
    const __m128 dist = _mm_sqrt_ps(dot4(dx, dy, dz, dx, dy, dz));
    __m128 exact = _mm_cmpeq_ps(dist, zero);  // lanes the scalar path must redo
    const __m128 angle1 = _mm_div_ps(dot4(n1x, n1y, n1z, dx, dy, dz), dist);
    const __m128 angle2 = _mm_div_ps(dot4(m2x, m2y, m2z, dx, dy, dz), dist);

    // Source choice: swap when |angle1| < |angle2|; near ties need acos itself.
    const __m128 abs1 = abs_ps(angle1), abs2 = abs_ps(angle2);
    const __m128 swap = _mm_cmplt_ps(abs1, abs2);
    const __m128 gap = abs_ps(_mm_sub_ps(abs1, abs2));
    const __m128 tie = _mm_cmpngt_ps(gap, _mm_set1_ps(2e-6f));
    exact = _mm_or_ps(exact,
                      _mm_and_ps(_mm_cmple_ps(gap, _mm_set1_ps(2e-6f)), _mm_cmpneq_ps(abs1, abs2)));
    const __m128 ux = select(swap, m2x, n1x), uy = select(swap, m2y, n1y),
                 uz = select(swap, m2z, n1z);
    const __m128 tx = select(swap, n1x, m2x), ty = select(swap, n1y, m2y),
                 tz = select(swap, n1z, m2z);
    const __m128 flip = _mm_and_ps(swap, sign);
    dx = _mm_xor_ps(dx, flip), dy = _mm_xor_ps(dy, flip), dz = _mm_xor_ps(dz, flip);
    const __m128 theta_value = select(swap, _mm_xor_ps(angle2, sign), angle1);

    // Darboux frame: v = delta x u / |delta x u|, w = u x v.
    __m128 vx = _mm_sub_ps(_mm_mul_ps(dy, uz), _mm_mul_ps(dz, uy));
    __m128 vy = _mm_sub_ps(_mm_mul_ps(dz, ux), _mm_mul_ps(dx, uz));
    __m128 vz = _mm_sub_ps(_mm_mul_ps(dx, uy), _mm_mul_ps(dy, ux));
    const __m128 v_norm = _mm_sqrt_ps(dot4(vx, vy, vz, vx, vy, vz));
    exact = _mm_or_ps(exact, _mm_cmpeq_ps(v_norm, zero));
    vx = _mm_div_ps(vx, v_norm), vy = _mm_div_ps(vy, v_norm), vz = _mm_div_ps(vz, v_norm);
    const __m128 wx = _mm_sub_ps(_mm_mul_ps(uy, vz), _mm_mul_ps(uz, vy));
    const __m128 wy = _mm_sub_ps(_mm_mul_ps(uz, vx), _mm_mul_ps(ux, vz));
    const __m128 wz = _mm_sub_ps(_mm_mul_ps(ux, vy), _mm_mul_ps(uy, vx));
    const __m128 phi_value = dot4(vx, vy, vz, tx, ty, tz);
    const __m128 y = dot4(wx, wy, wz, tx, ty, tz);
    const __m128 x = dot4(ux, uy, uz, tx, ty, tz);

    // alpha = atan2(y, x), approximated branch-free; only its bin is needed.
    const __m128 ax = abs_ps(x), ay = abs_ps(y);
    const __m128 largest = _mm_max_ps(ax, ay), smallest = _mm_min_ps(ax, ay);
    const __m128 degenerate = _mm_or_ps(_mm_cmpeq_ps(largest, zero), _mm_cmpeq_ps(y, zero));
    exact = _mm_or_ps(exact, degenerate);
    const __m128 a = _mm_div_ps(smallest, select(degenerate, _mm_set1_ps(1.0f), largest));
    const __m128 a2 = _mm_mul_ps(a, a);
    __m128 r = _mm_set1_ps(-0.01172120f);
    r = _mm_add_ps(_mm_mul_ps(r, a2), _mm_set1_ps(0.05265332f));
    r = _mm_add_ps(_mm_mul_ps(r, a2), _mm_set1_ps(-0.11643287f));
    r = _mm_add_ps(_mm_mul_ps(r, a2), _mm_set1_ps(0.19354346f));
    r = _mm_add_ps(_mm_mul_ps(r, a2), _mm_set1_ps(-0.33262347f));
    r = _mm_add_ps(_mm_mul_ps(r, a2), _mm_set1_ps(0.99997726f));
    r = _mm_mul_ps(r, a);
    r = select(_mm_cmpgt_ps(ay, ax), _mm_sub_ps(half_pi, r), r);
    r = select(_mm_cmplt_ps(x, zero), _mm_sub_ps(pi, r), r);
    r = _mm_xor_ps(r, _mm_and_ps(y, sign));
    const __m128 scaled = _mm_mul_ps(_mm_add_ps(r, pi), to_bins);
    const __m128i whole = _mm_cvttps_epi32(scaled);
    const __m128 fraction = _mm_sub_ps(scaled, _mm_cvtepi32_ps(whole));
    // 2e-5 rad of approximation error is < 4e-5 bins: decide only with a wide margin.
    exact = _mm_or_ps(exact, _mm_or_ps(_mm_cmplt_ps(fraction, _mm_set1_ps(5e-4f)),
                                       _mm_cmpgt_ps(fraction, _mm_set1_ps(1.0f - 5e-4f))));

    alignas(16) int alpha_bins[4];
    int phi_bins[4], theta_bins[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(alpha_bins), whole);
    cosine_bins(phi_value, bins, phi_bins);
    cosine_bins(theta_value, bins, theta_bins);
    store_lanes(4, _mm_movemask_ps(exact), _mm_movemask_ps(tie), alpha_bins, phi_bins, theta_bins,
                p1, n1, t, j, bins, alpha, phi, theta, one_sided);
  }
#endif
  for (; j < count; ++j) {
    exact_bins(p1, n1, t, j, bins, alpha, phi, theta);
    if (one_sided) one_sided[j] = 1;
  }
}

}  // namespace primlabel::detail
