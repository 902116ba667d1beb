// Eight bonds at a time with AVX-512, for the paper's compile-time (p,q) laws. The scalar sweep spends most
// of its time in one square root and one division per bond (both on the divider, ~2 ns per bond); here 1/r
// comes from the hardware estimate (rsqrt14, relative error < 2^-14) refined by two Newton steps
// y <- y (3/2 - r^2 y^2 / 2), which reach double precision (error ~2^-52, against the correctly rounded
// 1/sqrt). The steps are taken as y <- y (3 - r^2 y^2) and y <- y (12 - r^2 y^2), which carry y scaled by 2
// and then by 16, exactly (powers of two); the scale is taken out of G and H once, so the 1/2 r^2 product
// is saved. The law is F/r = ie^p (H ie^(q-p) - G) y, with ie = min(y, 1/r_min): one multiplication fewer
// than H ie^q - G ie^p. 17 multiplications per eight bonds in 2-D; the sweep is bound by them. Every bond, including the last partial vector of a thread's range, goes through the same masked
// vector arithmetic, so the result does not depend on how the range is split among threads.
#pragma once

#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__)
#define PMFRAG_HAVE_AVX512_SWEEP 1
// GCC 12 reports its own intrinsics' placeholder operands (_mm512_undefined_*) as maybe uninitialized.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>

#include "pair_kernels.hpp"  // pw<N>: GCC vector types multiply with *

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace pmfrag::detail {

/// Whether G and H keep full precision once scaled for the sweep below (false only for absurd laws).
template <int P, int Q>
inline bool fixed_avx512_scales(double G, double H) {
  return std::isnormal(std::ldexp(G, -4 * (P + 1))) && std::isnormal(std::ldexp(H, -4 * (Q + 1)));
}

/// Bonds (i, i + o) for i in [0, m) of one offset: F[i] = F(r)/r (x_i - x_{i+o}) (zero for bonds gone or
/// longer than sqrt(cut2)); returns the number of intact bonds found longer than sqrt(cut2).
template <int D, int P, int Q>
inline long sweep_fixed_avx512(const double* __restrict x0, const double* __restrict x1, const double* __restrict x2,
                               std::size_t o, const std::uint8_t* __restrict alive, double* __restrict F0,
                               double* __restrict F1, double* __restrict F2, std::size_t m,
                               double G, double H, double cut2, double inv_rmin) {
  static_assert(Q >= P, "the factored form needs q >= p");
  // y carries a factor s = 16: ie^p (H ie^(q-p) - G) y = (s ie)^p (H s^-(q+1) (s ie)^(q-p) - G s^-(p+1)) (s y)
  const __m512d vG = _mm512_set1_pd(std::ldexp(G, -4 * (P + 1))), vH = _mm512_set1_pd(std::ldexp(H, -4 * (Q + 1)));
  const __m512d vcut2 = _mm512_set1_pd(cut2), vrmin = _mm512_set1_pd(16.0 * inv_rmin);
  const __m512d three = _mm512_set1_pd(3.0), twelve = _mm512_set1_pd(12.0);
  long broke = 0;
  for (std::size_t i = 0; i < m; i += 8) {
    const std::size_t left = m - i;
    const __mmask8 lanes = left >= 8 ? __mmask8(0xff) : __mmask8((1u << left) - 1u);
    const __m512d d0 = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, x0 + i), _mm512_maskz_loadu_pd(lanes, x0 + i + o));
    const __m512d d1 = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, x1 + i), _mm512_maskz_loadu_pd(lanes, x1 + i + o));
    __m512d r2 = _mm512_fmadd_pd(d1, d1, _mm512_mul_pd(d0, d0));
    __m512d d2 = _mm512_setzero_pd();
    if constexpr (D == 3) {
      d2 = _mm512_sub_pd(_mm512_maskz_loadu_pd(lanes, x2 + i), _mm512_maskz_loadu_pd(lanes, x2 + i + o));
      r2 = _mm512_fmadd_pd(d2, d2, r2);
    }
    const __m128i a8 = _mm_maskz_loadu_epi8(lanes, alive + i);
    const __mmask8 live = _mm512_test_epi64_mask(_mm512_cvtepu8_epi64(a8), _mm512_set1_epi64(0xff)) & lanes;
    const __mmask8 within = _mm512_cmp_pd_mask(r2, vcut2, _CMP_LE_OQ);
    broke += __builtin_popcount(static_cast<unsigned>(live & static_cast<__mmask8>(~within)));
    const __m512d rr = _mm512_mask_blend_pd(live, vcut2, r2);  // no bond here: keep the arithmetic finite
    __m512d y = _mm512_rsqrt14_pd(rr);
    y = _mm512_mul_pd(y, _mm512_fnmadd_pd(rr, _mm512_mul_pd(y, y), three));   // 2 / r
    y = _mm512_mul_pd(y, _mm512_fnmadd_pd(rr, _mm512_mul_pd(y, y), twelve));  // 16 / r
    const __m512d ie = _mm512_min_pd(y, vrmin);  // force held constant inside r_min (Sec. 4.2)
    const __m512d iep = pw<P>(ie);
    const __m512d mag = _mm512_mul_pd(iep, _mm512_fmsub_pd(vH, pw<Q - P>(ie), vG));  // > 0 repulsive
    const __m512d fr = _mm512_maskz_mov_pd(live & within, _mm512_mul_pd(mag, y));
    if (left >= 8) {  // plain stores: a masked store cannot forward its data to the assembly's loads
      _mm512_storeu_pd(F0 + i, _mm512_mul_pd(fr, d0));
      _mm512_storeu_pd(F1 + i, _mm512_mul_pd(fr, d1));
      if constexpr (D == 3) _mm512_storeu_pd(F2 + i, _mm512_mul_pd(fr, d2));
    } else {
      _mm512_mask_storeu_pd(F0 + i, lanes, _mm512_mul_pd(fr, d0));
      _mm512_mask_storeu_pd(F1 + i, lanes, _mm512_mul_pd(fr, d1));
      if constexpr (D == 3) _mm512_mask_storeu_pd(F2 + i, lanes, _mm512_mul_pd(fr, d2));
    }
  }
  return broke;
}

}  // namespace pmfrag::detail
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif
