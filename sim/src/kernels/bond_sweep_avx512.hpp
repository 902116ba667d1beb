// The bond stencil's kernels in AVX-512: the sweep, eight bonds at a time for the paper's compile-time (p,q) laws
// (one law, or up to eight of them with each lane's looked up), and the block assemblies (at the end). The scalar
// sweep spends most of its time in one square root and one division per bond (both on the divider, ~2 ns per bond);
// here 1/r comes from the hardware estimate (rsqrt14, relative error < 2^-14) refined by two Newton steps y <- y
// (3/2 - r^2 y^2 / 2), which reach double precision (error ~2^-52, against the correctly rounded 1/sqrt). The steps
// are taken as y <- y (3 - r^2 y^2) and y <- y (12 - r^2 y^2), which carry y scaled by 2 and then by 16, exactly
// (powers of two); the scale is taken out of G and H once, so the 1/2 r^2 product is saved. The law is F/r = ie^p (H
// ie^(q-p) - G) y, with ie = min(y, 1/r_min): one multiplication fewer than H ie^q - G ie^p. 17 multiplications per
// eight bonds in 2-D; the sweep is bound by them. Every bond, including the last partial vector of a thread's range,
// goes through the same masked vector arithmetic, so the result does not depend on how the range is split among
// threads.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pmfrag::detail {
/// At most this many index offsets are swept (the block assembly keeps one back-offset per offset on its
/// stack); further offsets go through the pair table. The paper's bodies have 4 (plate) and 13 (3-D block).
inline constexpr std::size_t max_stencil_offsets = 64;

/// One offset of a group in the assembly: particle i receives -F[i - offset] where `lanes` has bit i % 8 of
/// byte i / 8 set (nullptr: every particle; the group's buffer then holds zeros where no bond is).
struct StencilTerm {
  std::size_t offset;
  const std::uint8_t* lanes;
};
}  // namespace pmfrag::detail

#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__) && !defined(PMFRAG_PORTABLE_KERNELS)
#define PMFRAG_HAVE_AVX512_SWEEP 1
// GCC 12 reports its own intrinsics' placeholder operands (_mm512_undefined_*) as maybe uninitialized.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>

#include "kernels/pair_kernels.hpp"  // pw<N>: GCC vector types multiply with *

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

namespace pmfrag::detail {

/// 2^k, exactly (a compile-time constant: a call to ldexp per sweep cost 4 % of the 3-D block's bond pass).
constexpr double pow2(int k) {
  double r = 1.0;
  for (; k > 0; --k) r *= 2.0;
  for (; k < 0; ++k) r *= 0.5;
  return r;
}

/// The sweeps' exact scalings of G and H (law_magnitude_avx512): 2^-4(p+1) and 2^-4(q+1).
constexpr double fixed_law_G_scale(int p) { return pow2(-4 * (p + 1)); }
constexpr double fixed_law_H_scale(int q) { return pow2(-4 * (q + 1)); }

/// Whether G and H keep full precision once scaled for the sweeps (false only for absurd laws). The scales are
/// compile-time constants: computed at run time, the loops in pow2 cost 4 % of the plate's step.
template <int P, int Q>
inline bool fixed_law_scales_ok(double G, double H) {
  constexpr double sG = fixed_law_G_scale(P), sH = fixed_law_H_scale(Q);
  return std::isnormal(G * sG) && std::isnormal(H * sH);
}

/// The first min(left, 8) lanes.
inline __mmask8 first_lanes(std::size_t left) { return left >= 8 ? __mmask8(0xff) : __mmask8((1u << left) - 1u); }

/// The loops below go eight elements at a time: body(i, std::true_type) for every full vector of [0, m), then
/// body(i, std::false_type) for the last, partial one if any. Full vectors use plain loads and stores: a masked
/// load cost ~7 % of the sweep's time even with every lane set (measured: 9.4 against 10.1 time-stamp cycles
/// per eight bonds), and a masked store cannot forward its data to the assembly's loads.
template <class Body>
[[gnu::always_inline]] inline void by_eight(std::size_t m, Body&& body) {
  std::size_t i = 0;
  for (; i + 8 <= m; i += 8) body(i, std::true_type{});
  if (i < m) body(i, std::false_type{});
}

/// Eight doubles from p: plainly for a full vector, else the lanes set in `lanes` (the others zero).
template <bool Full>
inline __m512d load_eight(__mmask8 lanes, const double* p) {
  if constexpr (Full) return _mm512_loadu_pd(p);
  return _mm512_maskz_loadu_pd(lanes, p);
}

/// Bonds (i, i + o) for i in [0, m) of one offset: F[i] = F(r)/r (x_i - x_{i+o}) (zero for bonds gone or
/// longer than sqrt(cut2)); returns the number of intact bonds found longer than sqrt(cut2). The pointers are at
/// i = 0, which lies `lead` slots past a multiple of eight particles (x, F 64-byte aligned there). The loop runs
/// on those aligned eights, the lanes outside [0, m) masked off. The law comes from
/// mag(i, ie, bonds, full): |F| (> 0 repulsive) from 16 ie (ie = min(1/r, 1/r_min)) for the lanes `bonds`,
/// scaled as below.
template <int D, class Mag>
inline long sweep_avx512(const double* __restrict x0, const double* __restrict x1, const double* __restrict x2,
                         std::size_t o, const std::uint8_t* __restrict alive, double* __restrict F0,
                         double* __restrict F1, double* __restrict F2, std::size_t m, std::size_t lead, double cut2,
                         double inv_rmin, Mag&& mag) {
  const __m512d vcut2 = _mm512_set1_pd(cut2), vrmin = _mm512_set1_pd(16.0 * inv_rmin);
  const __m512d three = _mm512_set1_pd(3.0), twelve = _mm512_set1_pd(12.0);
  long broke = 0;
  const auto eight = [&](std::ptrdiff_t i, __mmask8 lanes, auto full) __attribute__((always_inline)) {
    constexpr bool Full = decltype(full)::value;
    const __m512d d0 = _mm512_sub_pd(_mm512_load_pd(x0 + i), _mm512_loadu_pd(x0 + i + o));
    const __m512d d1 = _mm512_sub_pd(_mm512_load_pd(x1 + i), _mm512_loadu_pd(x1 + i + o));
    __m512d r2 = _mm512_fmadd_pd(d1, d1, _mm512_mul_pd(d0, d0));
    __m512d d2 = _mm512_setzero_pd();
    if constexpr (D == 3) {
      d2 = _mm512_sub_pd(_mm512_load_pd(x2 + i), _mm512_loadu_pd(x2 + i + o));
      r2 = _mm512_fmadd_pd(d2, d2, r2);
    }
    const __m128i a8 = Full ? _mm_loadl_epi64(reinterpret_cast<const __m128i*>(alive + i))
                            : _mm_maskz_loadu_epi8(lanes, alive + i);
    const __mmask8 live = _mm512_test_epi64_mask(_mm512_cvtepu8_epi64(a8), _mm512_set1_epi64(0xff)) & lanes;
    const __mmask8 within = _mm512_cmp_pd_mask(r2, vcut2, _CMP_LE_OQ);
    broke += __builtin_popcount(static_cast<unsigned>(live & static_cast<__mmask8>(~within)));
    const __m512d rr = _mm512_mask_blend_pd(live, vcut2, r2);  // no bond here: keep the arithmetic finite
    __m512d y = _mm512_rsqrt14_pd(rr);
    y = _mm512_mul_pd(y, _mm512_fnmadd_pd(rr, _mm512_mul_pd(y, y), three));   // 2 / r
    y = _mm512_mul_pd(y, _mm512_fnmadd_pd(rr, _mm512_mul_pd(y, y), twelve));  // 16 / r
    const __m512d ie = _mm512_min_pd(y, vrmin);  // force held constant inside r_min (Sec. 4.2)
    const __mmask8 bonds = live & within;
    const __m512d fr = _mm512_maskz_mov_pd(bonds, _mm512_mul_pd(mag(i, ie, bonds, full), y));
    if constexpr (Full) {
      _mm512_store_pd(F0 + i, _mm512_mul_pd(fr, d0));
      _mm512_store_pd(F1 + i, _mm512_mul_pd(fr, d1));
      if constexpr (D == 3) _mm512_store_pd(F2 + i, _mm512_mul_pd(fr, d2));
    } else {
      _mm512_mask_store_pd(F0 + i, lanes, _mm512_mul_pd(fr, d0));
      _mm512_mask_store_pd(F1 + i, lanes, _mm512_mul_pd(fr, d1));
      if constexpr (D == 3) _mm512_mask_store_pd(F2 + i, lanes, _mm512_mul_pd(fr, d2));
    }
  };
  const std::ptrdiff_t end = static_cast<std::ptrdiff_t>(m);
  std::ptrdiff_t i = -static_cast<std::ptrdiff_t>(lead);
  if (lead > 0) {
    const unsigned from = ~((1u << lead) - 1u);
    const unsigned to = end - i >= 8 ? 0xffu : (1u << (end - i)) - 1u;
    eight(i, __mmask8(from & to), std::false_type{});
    i += 8;
  }
  for (; i + 8 <= end; i += 8) eight(i, __mmask8(0xff), std::true_type{});
  if (i < end) eight(i, __mmask8((1u << (end - i)) - 1u), std::false_type{});
  return broke;
}

/// The (p,q) law's |F| from s ie (s = 16, the sweep's scaled 1/r) with G and H scaled by fixed_law_scales:
/// ie^p (H ie^(q-p) - G) y = (s ie)^p (H s^-(q+1) (s ie)^(q-p) - G s^-(p+1)) (s y), so the sweep's product with
/// s y is F/r exactly as unscaled (powers of two).
template <int P, int Q>
inline __m512d law_magnitude_avx512(__m512d ie, __m512d G_scaled, __m512d H_scaled) {
  static_assert(Q >= P, "the factored form needs q >= p");
  return _mm512_mul_pd(pw<P>(ie), _mm512_fmsub_pd(H_scaled, pw<Q - P>(ie), G_scaled));  // > 0 repulsive
}

/// sweep_avx512 for one law of compile-time exponents.
template <int D, int P, int Q>
inline long sweep_fixed_avx512(const double* __restrict x0, const double* __restrict x1, const double* __restrict x2,
                               std::size_t o, const std::uint8_t* __restrict alive, double* __restrict F0,
                               double* __restrict F1, double* __restrict F2, std::size_t m, std::size_t lead,
                               double G, double H, double cut2, double inv_rmin) {
  constexpr double sG = fixed_law_G_scale(P), sH = fixed_law_H_scale(Q);
  const __m512d vG = _mm512_set1_pd(G * sG), vH = _mm512_set1_pd(H * sH);
  return sweep_avx512<D>(x0, x1, x2, o, alive, F0, F1, F2, m, lead, cut2, inv_rmin,
                         [vG, vH](std::ptrdiff_t, __m512d ie, __mmask8, auto) __attribute__((always_inline)) {
                           return law_magnitude_avx512<P, Q>(ie, vG, vH);
                         });
}

/// sweep_fixed_avx512 for each law of the (p,q) sweeps, 1 <= p < q <= fixed_sweep_max_q (cases/sweep_pq.toml's
/// p = 1..14, q = p+1..15), looked up by p and q at run time: their exponents known at compile time, these laws
/// run as fast as the paper's three (tested against the plain force like every law). The run-time branches on
/// the exponents' bits in law_magnitude_avx512 below cost 10-15 % of a step; 105 instantiations per dimension
/// buy them back for the laws users sweep.
inline constexpr int fixed_sweep_max_q = 15;
template <int D>
using FixedSweep = long (*)(const double* __restrict, const double* __restrict, const double* __restrict, std::size_t,
                            const std::uint8_t* __restrict, double* __restrict, double* __restrict,
                            double* __restrict, std::size_t, std::size_t, double, double, double, double);
template <int D, int K>
constexpr FixedSweep<D> fixed_sweep_of() {  // K = 16 p + q
  constexpr int p = K / 16, q = K % 16;
  if constexpr (p >= 1 && p < q)
    return &sweep_fixed_avx512<D, p, q>;
  else
    return nullptr;
}
template <int D, int... K>
constexpr std::array<FixedSweep<D>, sizeof...(K)> fixed_sweeps(std::integer_sequence<int, K...>) {
  return {fixed_sweep_of<D, K>()...};
}
/// The sweep of law (p,q), or nullptr outside the table.
template <int D>
inline FixedSweep<D> fixed_sweep(int p, int q) {
  static_assert(fixed_sweep_max_q < 16);
  static constexpr auto table = fixed_sweeps<D>(std::make_integer_sequence<int, 256>{});
  if (p < 1 || q <= p || q > fixed_sweep_max_q) return nullptr;
  return table[static_cast<std::size_t>(16 * p + q)];
}

/// The (p,q) law's |F| for exponents known at run time, p and q - p below 2^Bits, from s ie (s = 16): the same
/// factored form as law_magnitude_avx512, with ie^p and ie^(q-p) from shared squarings of ie, a factor taken where
/// an exponent has its bit set (for q = 2p, one power). The bits are the same for every bond of the law, so the
/// branches are predicted, and a power's first factor is taken as it is (no product with 1). ie is unscaled first (one exact product):
/// (16 ie)^63 would leave the double range some 76 decades before ie^63 does. G and H come scaled by 1/16 for
/// the sweep's s y.
template <int Bits>
[[gnu::always_inline]] inline __m512d law_magnitude_avx512(__m512d s_ie, unsigned p, unsigned qp, __m512d G16,
                                                           __m512d H16) {
  __m512d sq = _mm512_mul_pd(s_ie, _mm512_set1_pd(0.0625));  // ie^(2^b) in round b
  __m512d ip = sq, iq = sq;
  const bool one_power = p == qp;  // q = 2p, as (1,2), (8,16), (16,32): ie^p serves both
#pragma GCC unroll 8
  for (int b = 0; b < Bits; ++b) {
    const unsigned bit = 1u << b, below = bit - 1u;
    if (p & bit) ip = (p & below) ? _mm512_mul_pd(ip, sq) : sq;
    if (!one_power && (qp & bit)) iq = (qp & below) ? _mm512_mul_pd(iq, sq) : sq;
    if (((p | qp) >> (b + 1)) == 0) break;
    sq = _mm512_mul_pd(sq, sq);
  }
  if (one_power) iq = ip;
  return _mm512_mul_pd(ip, _mm512_fmsub_pd(H16, iq, G16));  // > 0 repulsive
}

/// sweep_avx512 for one law of run-time exponents (1 <= p < q < 2^Bits): any law of the (p,q) sweeps, at the cost
/// of the multiplications its exponents' bits call for.
template <int D, int Bits>
inline long sweep_one_law_avx512(const double* __restrict x0, const double* __restrict x1,
                                 const double* __restrict x2, std::size_t o, const std::uint8_t* __restrict alive,
                                 double* __restrict F0, double* __restrict F1, double* __restrict F2, std::size_t m,
                                 std::size_t lead, int p, int q, double G, double H, double cut2, double inv_rmin) {
  const __m512d vG = _mm512_set1_pd(G * 0.0625), vH = _mm512_set1_pd(H * 0.0625);
  const unsigned up = static_cast<unsigned>(p), uqp = static_cast<unsigned>(q - p);
  return sweep_avx512<D>(x0, x1, x2, o, alive, F0, F1, F2, m, lead, cut2, inv_rmin,
                         [=](std::ptrdiff_t, __m512d ie, __mmask8, auto) __attribute__((always_inline)) {
                           return law_magnitude_avx512<Bits>(ie, up, uqp, vG, vH);
                         });
}

/// sweep_avx512 for bonds of several laws (a scene of several phases), each one of the paper's three (p,q):
/// bond i's law is ids[i], its scaled G, H and family in `table` (LawTable, usable). Each family present among the
/// eight bonds is evaluated for its lanes, with the arithmetic sweep_fixed_avx512 gives a scene of that one law.
template <int D>
inline long sweep_laws_avx512(const double* __restrict x0, const double* __restrict x1, const double* __restrict x2,
                              std::size_t o, const std::uint8_t* __restrict alive, const int* __restrict ids,
                              double* __restrict F0, double* __restrict F1, double* __restrict F2, std::size_t m,
                              std::size_t lead, const LawTable& table, double cut2, double inv_rmin) {
  const __m512d tG = _mm512_loadu_pd(table.G_scaled.data()), tH = _mm512_loadu_pd(table.H_scaled.data());
  const __m512i tF = _mm512_loadu_si512(table.family.data());
  return sweep_avx512<D>(
      x0, x1, x2, o, alive, F0, F1, F2, m, lead, cut2, inv_rmin,
      [&](std::ptrdiff_t i, __m512d ie, __mmask8 bonds, auto full) __attribute__((always_inline)) {
        constexpr bool Full = decltype(full)::value;
        const __m256i id8 = Full ? _mm256_loadu_si256(reinterpret_cast<const __m256i*>(ids + i))
                                 : _mm256_maskz_loadu_epi32(bonds, ids + i);
        const __m512i idx = _mm512_cvtepi32_epi64(id8);
        const __m512d G = _mm512_permutexvar_pd(idx, tG), H = _mm512_permutexvar_pd(idx, tH);
        const __m512i fam = _mm512_permutexvar_epi64(idx, tF);
        __m512d out = _mm512_setzero_pd();
        const auto family = [&](auto f) __attribute__((always_inline)) {  // f: the family, a compile-time index
          constexpr int P = paper_pq[decltype(f)::value][0], Q = paper_pq[decltype(f)::value][1];
          const __mmask8 lanes = _mm512_mask_cmpeq_epi64_mask(bonds, fam, _mm512_set1_epi64(decltype(f)::value));
          if (lanes) out = _mm512_mask_mov_pd(out, lanes, law_magnitude_avx512<P, Q>(ie, G, H));
        };
        family(std::integral_constant<int, 0>{});
        family(std::integral_constant<int, 1>{});
        family(std::integral_constant<int, 2>{});
        return out;
      });
}

/// f (N x D, interleaved) from particle k: f = 0 + a (Assign) or f + a, for the first min(left, 8) particles of
/// the block sums a (by component); the same bits as adding particle by particle.
template <int D, bool Assign>
inline void store_block_sums(const __m512d (&a)[D], double* fk, std::size_t left) {
  if constexpr (D == 2) {  // interleave (a0, a1) into x, y pairs: particles k..k+3 and k+4..k+7
    const __m512i lo = _mm512_set_epi64(11, 3, 10, 2, 9, 1, 8, 0), hi = _mm512_set_epi64(15, 7, 14, 6, 13, 5, 12, 4);
    if (left >= 8) {  // plain loads and stores (see by_eight)
      const __m512d f0 = Assign ? _mm512_setzero_pd() : _mm512_loadu_pd(fk);
      const __m512d f1 = Assign ? _mm512_setzero_pd() : _mm512_loadu_pd(fk + 8);
      _mm512_storeu_pd(fk, _mm512_add_pd(f0, _mm512_permutex2var_pd(a[0], lo, a[1])));
      _mm512_storeu_pd(fk + 8, _mm512_add_pd(f1, _mm512_permutex2var_pd(a[0], hi, a[1])));
      return;
    }
    const __mmask8 mlo = left >= 4 ? __mmask8(0xff) : __mmask8((1u << (2 * left)) - 1u);
    const __mmask8 mhi = left >= 8 ? __mmask8(0xff) : left > 4 ? __mmask8((1u << (2 * (left - 4))) - 1u) : __mmask8(0);
    const __m512d f0 = Assign ? _mm512_setzero_pd() : _mm512_maskz_loadu_pd(mlo, fk);
    const __m512d f1 = Assign ? _mm512_setzero_pd() : _mm512_maskz_loadu_pd(mhi, fk + 8);
    _mm512_mask_storeu_pd(fk, mlo, _mm512_add_pd(f0, _mm512_permutex2var_pd(a[0], lo, a[1])));
    _mm512_mask_storeu_pd(fk + 8, mhi, _mm512_add_pd(f1, _mm512_permutex2var_pd(a[0], hi, a[1])));
  } else {  // interleave (a0, a1, a2) into x, y, z triples: three vectors of eight, each from two permutes
    alignas(64) static constexpr long long xy[3][8] = {
        {0, 8, 0, 1, 9, 0, 2, 10}, {0, 3, 11, 0, 4, 12, 0, 5}, {13, 0, 6, 14, 0, 7, 15, 0}};
    alignas(64) static constexpr long long with_z[3][8] = {
        {0, 1, 8, 3, 4, 9, 6, 7}, {10, 1, 2, 11, 4, 5, 12, 7}, {0, 13, 2, 3, 14, 5, 6, 15}};
    const std::size_t values = 3 * (left < 8 ? left : 8);
    if (left >= 8) {
      for (std::size_t v = 0; v < 3; ++v) {
        const __m512d t = _mm512_permutex2var_pd(a[0], _mm512_load_si512(xy[v]), a[1]);
        const __m512d out = _mm512_permutex2var_pd(t, _mm512_load_si512(with_z[v]), a[2]);
        const __m512d old = Assign ? _mm512_setzero_pd() : _mm512_loadu_pd(fk + 8 * v);
        _mm512_storeu_pd(fk + 8 * v, _mm512_add_pd(old, out));
      }
      return;
    }
    for (std::size_t v = 0; v < 3; ++v) {
      const __mmask8 m = values >= 8 * (v + 1) ? __mmask8(0xff)
                         : values > 8 * v    ? __mmask8((1u << (values - 8 * v)) - 1u)
                                             : __mmask8(0);
      const __m512d t = _mm512_permutex2var_pd(a[0], _mm512_load_si512(xy[v]), a[1]);
      const __m512d out = _mm512_permutex2var_pd(t, _mm512_load_si512(with_z[v]), a[2]);
      const __m512d old = Assign ? _mm512_setzero_pd() : _mm512_maskz_loadu_pd(m, fk + 8 * v);
      _mm512_mask_storeu_pd(fk + 8 * v, m, _mm512_add_pd(old, out));
    }
  }
}

/// The assemblies' last step for eight particles from k: the block sums (a0, a1 and, in 3-D, a2) plus the
/// off-stencil sums extra[c][k..] if given, into f (store_block_sums).
template <int D, bool Assign, bool Full>
[[gnu::always_inline]] inline void finish_eight(__m512d a0, __m512d a1, __m512d a2, const double (*extra)[256],
                                                std::size_t k, __mmask8 lanes, double* f, std::size_t left) {
  if (extra) {
    a0 = _mm512_add_pd(a0, load_eight<Full>(lanes, extra[0] + k));
    a1 = _mm512_add_pd(a1, load_eight<Full>(lanes, extra[1] + k));
    if constexpr (D == 3) a2 = _mm512_add_pd(a2, load_eight<Full>(lanes, extra[2] + k));
  }
  if constexpr (D == 3) {
    const __m512d a[3] = {a0, a1, a2};
    store_block_sums<D, Assign>(a, f + k * D, left);
  } else {
    const __m512d a[2] = {a0, a1};
    store_block_sums<D, Assign>(a, f + k * D, left);
  }
}

/// The assembly of one block of len particles: f_i += sum over the offsets o_g of F_g[i] - F_g[i - o_g], then
/// + extra[i] if given, f (N x D, interleaved) from the block's first particle. Assign: f_i = 0 + the sum
/// instead (the same bits as adding to a zeroed f, without reading f). F_g's component c is the ring
/// at rows + (g D + c) stride: particle i at slot i & mask, the block's first at slot `at`; a ring's slots
/// from mask + 1 on repeat its first block, so F_g[i - o_g] is read on without wrapping. Eight particles at
/// a time with the sums in registers: through memory, the running sums were read back right after being
/// stored, and the loop ran at a quarter of its speed.
template <int D, bool Assign>
inline void assemble_block_avx512(const double* rows, std::size_t at, std::size_t mask, std::size_t stride,
                                  const std::size_t* offsets, std::size_t groups, const double (*extra)[256], double* f,
                                  std::size_t len) {
  std::ptrdiff_t back[max_stencil_offsets];  // from F_g[i] to F_g[i - o_g]
  for (std::size_t g = 0; g < groups; ++g)
    back[g] = static_cast<std::ptrdiff_t>((at + mask + 1 - offsets[g]) & mask) - static_cast<std::ptrdiff_t>(at);
  by_eight(len, [&](std::size_t k, auto full) {
    constexpr bool Full = decltype(full)::value;
    const std::size_t left = len - k;
    const __mmask8 lanes = first_lanes(left);
    const auto load = [&](const double* p) __attribute__((always_inline)) { return load_eight<Full>(lanes, p); };
    // named sums, not an array (see assemble_block_grouped_avx512)
    __m512d a0 = _mm512_setzero_pd(), a1 = _mm512_setzero_pd(), a2 = _mm512_setzero_pd();
    for (std::size_t g = 0; g < groups; ++g) {
      const double* F = rows + g * D * stride + at + k;
      a0 = _mm512_add_pd(a0, _mm512_sub_pd(load(F), load(F + back[g])));
      a1 = _mm512_add_pd(a1, _mm512_sub_pd(load(F + stride), load(F + stride + back[g])));
      if constexpr (D == 3)
        a2 = _mm512_add_pd(a2, _mm512_sub_pd(load(F + 2 * stride), load(F + 2 * stride + back[g])));
    }
    finish_eight<D, Assign, Full>(a0, a1, a2, extra, k, lanes, f, left);
  });
}

/// assemble_block_avx512 for the 2-D case of four offsets (the plate's 1, 39, 40, 41), with F_g[i - o_g] taken
/// from aligned loads. A back offset that is not a multiple of eight made every such load straddle two cache
/// lines (three of the plate's four), and the loop was bound by its loads (measured alone: 7.6 time-stamp
/// cycles per eight particles). Here each back stream is read one aligned vector ahead and the vector it
/// needs is cut from that one and the one before, kept in a register from the last eight (5.7 cycles alone).
/// The same numbers are added in the same order. A stream is read up to seven slots past the block's last back
/// slot, inside the ring's row (its stride has eight slots more than the ring and its repeated block); lanes
/// past the block's end are not stored. Written out for its eight streams: with arrays of them GCC kept the
/// carried vectors in memory.
template <bool Assign>
inline void assemble_block_four_avx512(const double* rows, std::size_t at, std::size_t mask, std::size_t stride,
                                       const std::size_t* offsets, const double (*extra)[256], double* f,
                                       std::size_t len) {
  struct Stream {
    const double* F;      // F_g's component from the block's first particle
    const double* ahead;  // the aligned vector at or below F_g[i - o_g] for the block's first i
    __m512d before;       // the aligned vector below the one to load next
    __m512i cut;          // lanes m .. m + 7 of (before, next)
  };
  const __m512i iota = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
  const auto stream = [&](std::size_t g, std::size_t c) __attribute__((always_inline)) {
    const std::size_t b = (at + mask + 1 - offsets[g]) & mask;  // slot of F_g[i - o_g] for the block's first i
    const std::size_t m = b & 7;  // the rows are 64-byte aligned and the stride is a multiple of eight
    const double* row = rows + (g * 2 + c) * stride;
    return Stream{row + at, row + (b - m), _mm512_load_pd(row + (b - m)),
                  _mm512_add_epi64(iota, _mm512_set1_epi64(static_cast<long long>(m)))};
  };
  Stream s00 = stream(0, 0), s01 = stream(0, 1), s10 = stream(1, 0), s11 = stream(1, 1);
  Stream s20 = stream(2, 0), s21 = stream(2, 1), s30 = stream(3, 0), s31 = stream(3, 1);
  const auto eight = [&](std::size_t k, auto full) __attribute__((always_inline)) {
    constexpr bool Full = decltype(full)::value;
    const std::size_t left = len - k;
    const __mmask8 lanes = first_lanes(left);
    const auto term = [&](Stream& st) __attribute__((always_inline)) {
      const __m512d next = _mm512_load_pd(st.ahead + k + 8);
      const __m512d back = _mm512_permutex2var_pd(st.before, st.cut, next);
      st.before = next;
      return _mm512_sub_pd(load_eight<Full>(lanes, st.F + k), back);
    };
    __m512d a0 = _mm512_add_pd(_mm512_setzero_pd(), term(s00));
    __m512d a1 = _mm512_add_pd(_mm512_setzero_pd(), term(s01));
    a0 = _mm512_add_pd(a0, term(s10));
    a1 = _mm512_add_pd(a1, term(s11));
    a0 = _mm512_add_pd(a0, term(s20));
    a1 = _mm512_add_pd(a1, term(s21));
    a0 = _mm512_add_pd(a0, term(s30));
    a1 = _mm512_add_pd(a1, term(s31));
    finish_eight<2, Assign, Full>(a0, a1, _mm512_setzero_pd(), extra, k, lanes, f, left);
  };
  by_eight(len, eight);
}

/// assemble_block_avx512 for groups of several offsets: f_i += sum over the groups g of F_g[i] - F_g[i - o] for each
/// of g's offsets o that reaches i (StencilTerm), then + extra[i] if given, f (N x D, interleaved) from the
/// block's first particle, lane0 = its index / 8. Assign: f_i = 0 + the sum instead (the same bits as adding to a
/// zeroed f, without reading f). F_g's component c is the ring at rows + (g D + c) stride: particle i at slot
/// i & mask, the block's first at slot `at`; a ring's slots from mask + 1 on repeat its first block, so
/// F_g[i - o] is read on without wrapping. Eight particles at a time with the sums in registers: through
/// memory, the running sums were read back right after being stored, and the loop ran at a quarter of its speed.
template <int D, bool Assign>
inline void assemble_block_grouped_avx512(const double* rows, std::size_t at, std::size_t mask, std::size_t stride,
                                  const StencilTerm* terms, const std::size_t* group_terms,
                                  const std::uint16_t* const* group_codes, std::size_t groups,
                                  std::size_t lane0, const double (*extra)[256], double* f, std::size_t len) {
  std::ptrdiff_t back[max_stencil_offsets];  // from F_g[i] to F_g[i - o], term by term
  std::size_t nterms = 0;
  for (std::size_t g = 0; g < groups; ++g) nterms += group_terms[g];
  for (std::size_t t = 0; t < nterms; ++t)
    back[t] = static_cast<std::ptrdiff_t>((at + mask + 1 - terms[t].offset) & mask) - static_cast<std::ptrdiff_t>(at);
  // The sums in three named vectors, not an array: GCC kept a[D] in memory here, and each of the 24 additions
  // of the 3-D block waited for the last one's store to be read back (measured: 68 time-stamp cycles per
  // eight particles). For D = 2 the third stays zero and is not stored.
  const auto eight = [&](std::size_t k, auto full) __attribute__((always_inline)) {
    constexpr bool Full = decltype(full)::value;
    const std::size_t left = len - k;
    const __mmask8 lanes = first_lanes(left);
    const auto load = [&](const double* p) __attribute__((always_inline)) { return load_eight<Full>(lanes, p); };
    __m512d a0 = _mm512_setzero_pd(), a1 = _mm512_setzero_pd(), a2 = _mm512_setzero_pd();
    // F_g[i] less the vector `behind(F)` gives for F = F_g's component c, into that component's sum
    const auto add = [&](const double* Fg, auto&& behind) __attribute__((always_inline)) {
      a0 = _mm512_add_pd(a0, _mm512_sub_pd(load(Fg), behind(Fg)));
      a1 = _mm512_add_pd(a1, _mm512_sub_pd(load(Fg + stride), behind(Fg + stride)));
      if constexpr (D == 3) a2 = _mm512_add_pd(a2, _mm512_sub_pd(load(Fg + 2 * stride), behind(Fg + 2 * stride)));
    };
    std::size_t t0 = 0;
    for (std::size_t g = 0; g < groups; t0 += group_terms[g], ++g) {
      const double* Fg = rows + g * D * stride + at + k;
      if (group_terms[g] == 1) {  // one offset: the buffer holds zeros where no bond is
        const std::ptrdiff_t b = back[t0];
        add(Fg, [&](const double* F) __attribute__((always_inline)) { return load(F + b); });
        continue;
      }
      // Several offsets: each particle receives from at most one of them (their bonds share no second
      // particle), so F[i - o] is read at that one offset, or gathered by merging masked loads where the
      // eight particles take it from several; either way it is subtracted once.
      const unsigned code = group_codes[g][lane0 + k / 8];
      if ((code >> 8) != 0xff) {  // one offset reaches these eight (most of them: a row is 40-41 long)
        const std::ptrdiff_t b = back[t0 + (code >> 8)];
        const __mmask8 m = __mmask8(code & lanes);
        add(Fg, [&](const double* F) __attribute__((always_inline)) { return _mm512_maskz_loadu_pd(m, F + b); });
        continue;
      }
      __mmask8 reach[max_stencil_offsets];
      const std::size_t nt = group_terms[g];
      for (std::size_t t = 0; t < nt; ++t) reach[t] = __mmask8(terms[t0 + t].lanes[lane0 + k / 8] & lanes);
      add(Fg, [&](const double* F) __attribute__((always_inline)) {
        __m512d v = _mm512_maskz_loadu_pd(reach[0], F + back[t0]);
        for (std::size_t t = 1; t < nt; ++t) v = _mm512_mask_loadu_pd(v, reach[t], F + back[t0 + t]);
        return v;
      });
    }
    finish_eight<D, Assign, Full>(a0, a1, a2, extra, k, lanes, f, left);
  };
  by_eight(len, eight);
}

}  // namespace pmfrag::detail
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif
