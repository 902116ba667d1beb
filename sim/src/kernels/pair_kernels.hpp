// Internal pieces of the pair effect: the law evaluators the loops are templated on (so the (p,q) law is
// inlined; the paper's three laws get compile-time exponents) and a pair table with a per-particle gather.
#pragma once

#include "pmfrag/kernels/aligned.hpp"

#include "pmfrag/model/pair_law.hpp"
#include "threads/team.hpp"

#include <Eigen/Core>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace pmfrag::detail {

template <int N, class T>
inline T pw(T x) {
  if constexpr (N == 0) {
    return T(1);
  } else if constexpr (N == 1) {
    return x;
  } else if constexpr (N % 2 == 0) {
    const T h = pw<N / 2>(x);
    return h * h;
  } else {
    return x * pw<N - 1>(x);
  }
}

/// |F| of the law from 1/r, positive = repulsive, in the arithmetic of T (double, or float for the
/// precision knob). `with_ids` binds the per-pair law index array of a loop.
template <int P, int Q>
struct FixedLaw {
  static constexpr int p = P, q = Q;
  double G, H;
  template <class T = double>
  T magnitude(std::size_t, T ie) const {
    return -T(G) * pw<P>(ie) + T(H) * pw<Q>(ie);
  }
  FixedLaw with_ids(const int*) const { return *this; }
};
template <class Law>
struct is_fixed_law : std::false_type {};
template <int P, int Q>
struct is_fixed_law<FixedLaw<P, Q>> : std::true_type {};

/// x^p and x^q for exponents below 2^Bits, in Bits fixed rounds that select a factor of x or 1 instead of
/// branching on the bits: a loop over pairs calling it vectorizes (the branching ipow kept the loop scalar,
/// and a law outside the paper's three ran 1.6-1.8x slower than (7,14) on the portable kernels, 5-7x on the
/// AVX-512 machine). The squarings serve both exponents. The products are those of ipow in the same order
/// (a factor of 1 where a bit is clear changes nothing), so the bits are ipow's.
/// take ? x : 1, by bit operations (a ?: here became a branch, and GCC 12 then left the loop scalar).
template <class T>
inline T x_or_one(T x, unsigned take) {
  using U = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
  const U m = U(0) - static_cast<U>(take & 1u);
  return std::bit_cast<T>(static_cast<U>((std::bit_cast<U>(x) & m) | (std::bit_cast<U>(T(1)) & ~m)));
}
template <int Bits, class T>
inline void two_powers(T x, int p, int q, T& xp, T& xq) {
  T rp = T(1), rq = T(1);
  const unsigned up = static_cast<unsigned>(p), uq = static_cast<unsigned>(q);
#pragma GCC unroll 8
  for (int b = 0; b < Bits; ++b) {
    rp *= x_or_one(x, up >> b);
    rq *= x_or_one(x, uq >> b);
    x *= x;
  }
  xp = rp, xq = rq;
}

/// One law with exponents known at run time, q < 2^Bits (with_law picks Bits from q).
template <int Bits>
struct OneLaw {
  static constexpr int bits = Bits;
  PairLaw law;
  /// G 2^-4(p+1) and H 2^-4(q+1), the AVX-512 sweeps' exact scalings, stay normal (once per evaluator: per
  /// sweep, ldexp cost 4 % of a step)
  bool scales_ok = std::isnormal(std::ldexp(law.G, -4 * (law.p + 1))) && std::isnormal(std::ldexp(law.H, -4 * (law.q + 1)));
  template <class T = double>
  T magnitude(std::size_t, T ie) const {
    T ip, iq;
    two_powers<Bits>(ie, law.p, law.q, ip, iq);
    if constexpr (std::is_same_v<T, double>) return -law.G * ip + law.H * iq;
    return -T(law.G) * ip + T(law.H) * iq;
  }
  OneLaw with_ids(const int*) const { return *this; }
};
template <class Law>
struct is_one_law : std::false_type {};
template <int Bits>
struct is_one_law<OneLaw<Bits>> : std::true_type {};
/// Enough rounds for every exponent a law may have (max_exponent = 64).
inline constexpr int exponent_bits = 7;
/// The paper's three (p,q) laws; a law's family in LawTable is its index here.
inline constexpr int paper_pq[3][2] = {{3, 5}, {5, 10}, {7, 14}};

/// What the AVX-512 sweep of several laws (sweep_laws_avx512) needs of them, built once per set of laws:
/// usable if there are at most eight and each is one of paper_pq; per law G 2^-4(p+1) and H 2^-4(q+1) (the
/// sweeps' exact scalings, kept normal) and its family.
struct LawTable {
  bool usable = false;
  std::array<double, 8> G_scaled{}, H_scaled{};
  std::array<long long, 8> family{};

  LawTable() = default;
  explicit LawTable(const std::vector<PairLaw>& laws) {
    usable = laws.size() <= 8;
    for (std::size_t l = 0; l < laws.size() && usable; ++l) {
      const PairLaw& law = laws[l];
      family[l] = -1;
      for (long long f = 0; f < 3; ++f)
        if (law.p == paper_pq[f][0] && law.q == paper_pq[f][1]) family[l] = f;
      G_scaled[l] = std::ldexp(law.G, -4 * (law.p + 1));
      H_scaled[l] = std::ldexp(law.H, -4 * (law.q + 1));
      usable = family[l] >= 0 && std::isnormal(G_scaled[l]) && std::isnormal(H_scaled[l]);
    }
  }
};

struct ManyLaws {
  const PairLaw* laws;
  const int* id;
  const LawTable* table;  ///< for the vector sweep
  template <class T = double>
  T magnitude(std::size_t u, T ie) const {
    const PairLaw& l = laws[id[u]];
    T ip, iq;
    two_powers<exponent_bits>(ie, l.p, l.q, ip, iq);
    if constexpr (std::is_same_v<T, double>) return -l.G * ip + l.H * iq;
    return -T(l.G) * ip + T(l.H) * iq;
  }
  ManyLaws with_ids(const int* ids) const { return ManyLaws{laws, ids, table}; }
};

/// Calls fn(evaluator) with the fastest evaluator that fits: a single law (compile-time exponents for the
/// paper's (3,5), (5,10), (7,14); otherwise as many rounds of squaring as q has bits) or a per-pair law
/// lookup (`table`: LawTable(laws)).
template <class Fn>
auto with_law(const std::vector<PairLaw>& laws, const LawTable& table, bool single, Fn&& fn) {
  if (single) {
    const PairLaw& l = laws.front();
    if (l.p == 7 && l.q == 14) return fn(FixedLaw<7, 14>{l.G, l.H});
    if (l.p == 5 && l.q == 10) return fn(FixedLaw<5, 10>{l.G, l.H});
    if (l.p == 3 && l.q == 5) return fn(FixedLaw<3, 5>{l.G, l.H});
    static_assert(max_exponent < (1 << exponent_bits));
    switch (std::bit_width(static_cast<unsigned>(l.q))) {
      case 0:
      case 1:
      case 2: return fn(OneLaw<2>{l});
      case 3: return fn(OneLaw<3>{l});
      case 4: return fn(OneLaw<4>{l});
      case 5: return fn(OneLaw<5>{l});
      case 6: return fn(OneLaw<6>{l});
      default: return fn(OneLaw<exponent_bits>{l});
    }
  }
  return fn(ManyLaws{laws.data(), nullptr, &table});
}

/// Potential with the r_min clamp continued linearly (phi' = -F, F constant inside r_min).
inline double law_potential(const PairLaw& law, double r, double r_min) {
  if (r >= r_min) return law.potential(r);
  return law.potential(r_min) + law.force(r_min) * (r_min - r);
}

/// Pairs (i < j) with per-pair law and force, and per-particle incidence for a gather in fixed order.
template <int D>
struct PairTable {
  using V = Eigen::Matrix<double, D, 1>;
  std::vector<int> i, j, law;
  std::vector<double, AlignedAllocator<double>> force[D];  ///< components of the force on i (j gets the opposite)
  std::vector<int> offset, entry;  ///< CSR: entry = pair << 1 | (particle is j)
  std::vector<int> touched;        ///< particles with at least one pair (the gather visits only these)

  std::size_t size() const { return i.size(); }
  void clear() { i.clear(), j.clear(), law.clear(); }
  void add(int a, int b, int l) { i.push_back(a), j.push_back(b), law.push_back(l); }
  void index(std::size_t n) {
    for (auto& c : force) c.assign(size(), 0.0);
    offset.assign(n + 1, 0);
    for (std::size_t p = 0; p < size(); ++p)
      ++offset[static_cast<std::size_t>(i[p]) + 1], ++offset[static_cast<std::size_t>(j[p]) + 1];
    for (std::size_t k = 0; k < n; ++k) offset[k + 1] += offset[k];
    entry.resize(static_cast<std::size_t>(offset[n]));
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (std::size_t p = 0; p < size(); ++p) {  // ascending p: a fixed order per particle
      entry[static_cast<std::size_t>(fill[static_cast<std::size_t>(i[p])]++)] = static_cast<int>(p << 1);
      entry[static_cast<std::size_t>(fill[static_cast<std::size_t>(j[p])]++)] = static_cast<int>(p << 1 | 1);
    }
    touched.clear();
    for (std::size_t k = 0; k < n; ++k)
      if (offset[k + 1] > offset[k]) touched.push_back(static_cast<int>(k));
  }
  /// The pair forces' components (force, or another thread's copy of them).
  using Forces = std::array<const double*, D>;
  Forces forces() const {
    Forces F;
    for (int c = 0; c < D; ++c) F[static_cast<std::size_t>(c)] = force[c].data();
    return F;
  }
  /// s = the sum of particle k's pair forces, in its fixed (ascending pair) order.
  void sum_of(std::size_t k, double (&s)[D]) const { sum_of(k, s, forces()); }
  void sum_of(std::size_t k, double (&s)[D], const Forces& F) const {
    for (int c = 0; c < D; ++c) s[c] = 0.0;
    for (int e = offset[k]; e < offset[k + 1]; ++e) {
      const int en = entry[static_cast<std::size_t>(e)];
      const std::size_t p = static_cast<std::size_t>(en >> 1);
      // j gets -F. A select, not a multiplication by a sign made with an int-to-double conversion: that
      // conversion writes half a register and stalled this loop on the previous one's result.
      for (int c = 0; c < D; ++c) {
        const double Fc = F[static_cast<std::size_t>(c)][p];
        s[c] += (en & 1) ? -Fc : Fc;
      }
    }
  }
  /// f_k += sum of its pairs' forces: thread tid of nt does its share of the particles.
  void gather(double* f, int tid, int nt) const {
    const auto [first, last] = share(static_cast<long>(touched.size()), tid, nt);
    gather_touched(f, first, last);
  }
  /// The same for the particles touched[first, last).
  void gather_touched(double* f, long first, long last) const { gather_touched(f, first, last, forces()); }
  void gather_touched(double* f, long first, long last, const Forces& F) const {
    for (long t = first; t < last; ++t) {
      const std::size_t k = static_cast<std::size_t>(touched[static_cast<std::size_t>(t)]);
      double s[D];
      sum_of(k, s, F);
      for (int c = 0; c < D; ++c) f[k * D + static_cast<std::size_t>(c)] += s[c];
    }
  }
};

}  // namespace pmfrag::detail
