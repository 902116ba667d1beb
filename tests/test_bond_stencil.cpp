// The bond stencil's groups (sim/src/kernels/bond_stencil.hpp): in a large body, index offsets whose bonds share no
// particle are swept into one buffer, and the assembly reads it back under lane masks. Checked here against
// the same stencil with one group per offset and against a plain sum over the intact bonds, with bonds broken
// in every group, on one and two threads.
#include "kernels/bond_stencil.hpp"
#include "pmfrag/body/scene.hpp"
#include "pmfrag/body/system.hpp"
#include "pmfrag/model/material.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

using namespace pmfrag;

namespace {
// The particles' positions (N x dim), each moved at random by up to 2 % of r0 so that every bond carries a force.
std::vector<double> jittered(const System& sys, int dim, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> jitter(-0.02 * sys.r0, 0.02 * sys.r0);
  const std::size_t d = static_cast<std::size_t>(dim);
  std::vector<double> x(d * sys.size());
  for (std::size_t i = 0; i < sys.size(); ++i)
    for (std::size_t c = 0; c < d; ++c) x[d * i + c] = sys.position[i][static_cast<Eigen::Index>(c)] + jitter(rng);
  return x;
}
}  // namespace

TEST(BondStencil, MergedOffsetsGiveTheForcesOfOneGroupPerOffset) {
  // The paper's 3-D block without its slit (its 13 offsets; rings far larger than L2, so they merge), every
  // particle moved at random by up to 2 % of r0 so that each bond carries a real force.
  const Scene sc = read_scene(test::case_path("block3d_slit.toml"), {"body.0.slits=[]"});
  System sys = build_system(sc);
  const std::size_t n = sys.size();
  std::mt19937_64 rng(11);
  const std::vector<double> x = jittered(sys, 3, rng);
  std::vector<int> bi, bj, blaw;
  for (const auto& b : sys.bonds) bi.push_back(b[0]), bj.push_back(b[1]), blaw.push_back(0);
  detail::BondStencil<3> merged(n, bi, bj, blaw), separate(n, bi, bj, blaw, false, false);
  EXPECT_EQ(separate.groups(), 13u) << "the block's offsets: 1, 40-42, 778-780, 819-821, 860-862";
  EXPECT_EQ(merged.groups(), 8u) << "the fewest groups the block's conflicting offsets allow";
  // a fifth of the bonds broken, at random: each group loses bonds at each of its offsets
  std::bernoulli_distribution broken(0.2);
  std::vector<bool> alive(bi.size(), true);
  for (std::size_t b = 0; b < bi.size(); ++b)
    if (broken(rng)) {
      alive[b] = false;
      merged.set_alive(bi[b], bj[b], false);
      separate.set_alive(bi[b], bj[b], false);
    }
  const PairLaw& law = sys.laws[0];
  ASSERT_EQ(law.p, 7);
  ASSERT_EQ(law.q, 14);
  const detail::FixedLaw<7, 14> fixed{law.G, law.H};
  const double cut2 = sys.cutoff * sys.cutoff, inv_rmin = INFINITY;
  std::vector<double> plain(3 * n, 0.0);
  double scale = 0.0;
  for (std::size_t b = 0; b < bi.size(); ++b) {
    if (!alive[b]) continue;
    const std::size_t i = static_cast<std::size_t>(bi[b]), j = static_cast<std::size_t>(bj[b]);
    double d[3], r2 = 0.0;
    for (int c = 0; c < 3; ++c) d[c] = x[3 * i + static_cast<std::size_t>(c)] - x[3 * j + static_cast<std::size_t>(c)], r2 += d[c] * d[c];
    const double r = std::sqrt(r2), fr = law.force(r) / r;
    for (int c = 0; c < 3; ++c) {
      plain[3 * i + static_cast<std::size_t>(c)] += fr * d[c];
      plain[3 * j + static_cast<std::size_t>(c)] -= fr * d[c];
    }
  }
  for (double v : plain) scale = std::max(scale, std::abs(v));
  ASSERT_GT(scale, 1e3) << "dyn: the jitter should load the bonds";
  std::vector<double> first;
  for (int threads : {1, 2}) {
    detail::Team team(threads);
    std::vector<double> fm(3 * n, 0.0), fs(3 * n, 0.0);
    EXPECT_EQ(merged.add_forces(team, x.data(), fm.data(), fixed, cut2, inv_rmin), 0);
    EXPECT_EQ(separate.add_forces(team, x.data(), fs.data(), fixed, cut2, inv_rmin), 0);
    double vs_separate = 0.0, vs_plain = 0.0;
    for (std::size_t k = 0; k < 3 * n; ++k)
      vs_separate = std::max(vs_separate, std::abs(fm[k] - fs[k])), vs_plain = std::max(vs_plain, std::abs(fm[k] - plain[k]));
    // the two layouts add the same bond forces in another order
    EXPECT_LT(vs_separate, 1e-13 * scale) << threads << " thread(s)";
    EXPECT_LT(vs_plain, 1e-9 * scale) << threads << " thread(s)";
    if (first.empty())
      first = fm;
    else
      EXPECT_EQ(std::memcmp(first.data(), fm.data(), fm.size() * sizeof(double)), 0) << "1 and 2 threads";
  }
}

// A scene of several phases (the shipped inclusion: a (3,5) matrix, a (7,14) inclusion, a weaker (3,5)
// interface) sweeps its bonds eight at a time with each lane's law looked up (sweep_laws_avx512 where the
// machine has AVX-512); a law outside the paper's three exponent pairs sends every bond through the scalar
// loop. Both are checked against a plain sum over the intact bonds, each with its own law's force.
namespace {
template <std::size_t D = 2>
std::vector<double> plain_bond_forces(const std::vector<double>& x, const std::vector<int>& bi,
                                      const std::vector<int>& bj, const std::vector<int>& blaw,
                                      const std::vector<bool>& alive, const std::vector<PairLaw>& laws) {
  std::vector<double> f(x.size(), 0.0);
  for (std::size_t b = 0; b < bi.size(); ++b) {
    if (!alive[b]) continue;
    const std::size_t i = static_cast<std::size_t>(bi[b]), j = static_cast<std::size_t>(bj[b]);
    double d[D], r2 = 0.0;
    for (std::size_t c = 0; c < D; ++c) d[c] = x[D * i + c] - x[D * j + c], r2 += d[c] * d[c];
    const double r = std::sqrt(r2);
    const double fr = laws[static_cast<std::size_t>(blaw[b])].force(r) / r;
    for (std::size_t c = 0; c < D; ++c) f[D * i + c] += fr * d[c], f[D * j + c] -= fr * d[c];
  }
  return f;
}
}  // namespace

TEST(BondStencil, SeveralLawsGiveEachBondItsOwnLaw) {
  const Scene sc = read_scene(test::case_path("inclusion.toml"));
  const System sys = build_system(sc);
  ASSERT_EQ(sys.laws.size(), 3u) << "matrix, inclusion, interface";
  const std::size_t n = sys.size();
  std::mt19937_64 rng(5);
  const std::vector<double> x = jittered(sys, 2, rng);
  std::vector<int> bi, bj, blaw;
  int counts[3] = {0, 0, 0};
  for (const auto& b : sys.bonds) {
    bi.push_back(b[0]), bj.push_back(b[1]);
    const auto& a = sys.phase_pair_law;
    const std::size_t np = sys.phase_names.size();
    blaw.push_back(a[static_cast<std::size_t>(sys.phase[static_cast<std::size_t>(b[0])]) * np +
                     static_cast<std::size_t>(sys.phase[static_cast<std::size_t>(b[1])])]);
    ++counts[blaw.back()];
  }
  for (int l = 0; l < 3; ++l) EXPECT_GT(counts[l], 50) << "law " << l << " has bonds";
  std::bernoulli_distribution broken(0.1);
  std::vector<bool> alive(bi.size(), true);
  detail::BondStencil<2> stencil(n, bi, bj, blaw);
  for (std::size_t b = 0; b < bi.size(); ++b)
    if (broken(rng)) alive[b] = false, stencil.set_alive(bi[b], bj[b], false);
  const double cut2 = sys.cutoff * sys.cutoff, inv_rmin = INFINITY;

  const auto check = [&](const std::vector<PairLaw>& laws, bool vector_table) {
    const detail::LawTable table(laws);
    const detail::ManyLaws many{laws.data(), nullptr, &table};
    EXPECT_EQ(table.usable, vector_table);
    const std::vector<double> plain = plain_bond_forces(x, bi, bj, blaw, alive, laws);
    double scale = 0.0;
    for (double v : plain) scale = std::max(scale, std::abs(v));
    ASSERT_GT(scale, 1e3) << "dyn: the jitter should load the bonds";
    std::vector<double> first;
    for (int threads : {1, 2}) {
      detail::Team team(threads);
      std::vector<double> f(2 * n, 0.0);
      EXPECT_EQ(stencil.add_forces(team, x.data(), f.data(), many, cut2, inv_rmin), 0);
      double worst = 0.0;
      for (std::size_t k = 0; k < 2 * n; ++k) worst = std::max(worst, std::abs(f[k] - plain[k]));
      EXPECT_LT(worst, 1e-12 * scale) << threads << " thread(s)";
      if (first.empty())
        first = f;
      else
        EXPECT_EQ(std::memcmp(first.data(), f.data(), f.size() * sizeof(double)), 0) << "1 and 2 threads";
    }
  };
  check(sys.laws, true);
  // the inclusion's law with another repulsive exponent: no table, the scalar loop
  std::vector<PairLaw> odd = sys.laws;
  odd[1].q = 12;
  check(odd, false);
}

// Every law of the (p,q) sweeps, one law a scene, through the evaluator the engine picks (with_law): the paper's
// three with compile-time exponents, the others with run-time ones. Each is checked against a plain sum of
// PairLaw::force over the intact bonds, on the plate and on the 3-D block, and for the same bits on one and two
// threads.
namespace {
template <int D>
void check_every_law(const System& sys, std::uint64_t seed) {
  const std::size_t n = sys.size();
  std::mt19937_64 rng(seed);
  const std::vector<double> x = jittered(sys, D, rng);
  std::vector<int> bi, bj, blaw;
  for (const auto& b : sys.bonds) bi.push_back(b[0]), bj.push_back(b[1]), blaw.push_back(0);
  detail::BondStencil<D> stencil(n, bi, bj, blaw);
  std::bernoulli_distribution broken(0.1);
  std::vector<bool> alive(bi.size(), true);
  for (std::size_t b = 0; b < bi.size(); ++b)
    if (broken(rng)) alive[b] = false, stencil.set_alive(bi[b], bj[b], false);
  const double cut2 = sys.cutoff * sys.cutoff, inv_rmin = INFINITY;
  for (const auto& [p, q] : std::vector<std::array<int, 2>>{
           {1, 2}, {2, 3}, {3, 5}, {4, 9}, {5, 10}, {6, 12}, {7, 14}, {7, 15}, {8, 16}, {13, 14}, {14, 15},
           {16, 32}, {31, 64}, {63, 64}}) {
    const std::vector<PairLaw> laws{derive_material(p, q, sys.r0).law};
    const detail::LawTable table(laws);
    const std::vector<double> plain = plain_bond_forces<D>(x, bi, bj, blaw, alive, laws);
    double scale = 0.0;
    for (double v : plain) scale = std::max(scale, std::abs(v));
    ASSERT_GT(scale, 0.0);
    std::vector<double> first;
    for (int threads : {1, 2}) {
      detail::Team team(threads);
      std::vector<double> f(x.size(), 0.0);
      const long beyond = detail::with_law(laws, table, true, [&](const auto& law) {
        return stencil.add_forces(team, x.data(), f.data(), law, cut2, inv_rmin);
      });
      EXPECT_EQ(beyond, 0) << "(" << p << "," << q << ")";
      double worst = 0.0;
      for (std::size_t k = 0; k < f.size(); ++k) worst = std::max(worst, std::abs(f[k] - plain[k]));
      EXPECT_LT(worst, 1e-12 * scale) << "(" << p << "," << q << "), " << threads << " thread(s)";
      if (first.empty())
        first = f;
      else
        EXPECT_EQ(std::memcmp(first.data(), f.data(), f.size() * sizeof(double)), 0)
            << "(" << p << "," << q << "), 1 and 2 threads";
    }
  }
}
}  // namespace

TEST(BondStencil, EveryLawOfTheSweepsMatchesItsPlainForce) {
  check_every_law<2>(build_system(read_scene(test::case_path("slit_plate_7_14.toml"))), 21);
  check_every_law<3>(build_system(read_scene(test::case_path("block3d_slit.toml"), {"body.0.slits=[]"})), 22);
}

TEST(BondStencil, OneLawLayoutAndBondLookupGiveTheSameForces) {
  // The slit plate's bonds, plus five far-reaching ones whose offsets no sweep takes (off the stencil, like
  // bonds between bodies): set_alive finds those by bisection and the rest by offset. A stencil that keeps no
  // law per bond (one phase) must give the bits of one that does.
  const Scene sc = read_scene(test::case_path("slit_plate_7_14.toml"));
  System sys = build_system(sc);
  const std::size_t n = sys.size();
  std::mt19937_64 rng(5);
  const std::vector<double> x = jittered(sys, 2, rng);
  std::vector<std::array<int, 2>> bonds = sys.bonds;
  for (int k = 0; k < 5; ++k) bonds.push_back({100 * k, 100 * k + static_cast<int>(n) / 2 + k});
  std::sort(bonds.begin(), bonds.end());
  std::vector<int> bi, bj, blaw;
  for (const auto& b : bonds) bi.push_back(b[0]), bj.push_back(b[1]), blaw.push_back(0);
  detail::BondStencil<2> with_laws(n, bi, bj, blaw), one_law(n, bi, bj, blaw, false, true, false);
  EXPECT_THROW(one_law.set_alive(0, static_cast<int>(n) - 1, false), std::logic_error) << "not a bond";
  const PairLaw& law = sys.laws[0];
  const detail::FixedLaw<7, 14> fixed{law.G, law.H};
  const double cut2 = sys.cutoff * sys.cutoff;
  detail::Team team(2);
  std::vector<double> f(2 * n, 0.0);
  EXPECT_GE(one_law.add_forces(team, x.data(), f.data(), fixed, cut2, INFINITY), 5) << "the far bonds are too long";
  std::bernoulli_distribution broken(0.3);
  for (std::size_t b = 0; b < bi.size(); ++b)
    if (broken(rng) || bj[b] - bi[b] > 100) with_laws.set_alive(bi[b], bj[b], false), one_law.set_alive(bi[b], bj[b], false);
  std::vector<double> fa(2 * n, 0.0), fb(2 * n, 0.0);
  EXPECT_EQ(with_laws.add_forces(team, x.data(), fa.data(), fixed, cut2, INFINITY), 0) << "the far bonds are retired";
  EXPECT_EQ(one_law.add_forces(team, x.data(), fb.data(), fixed, cut2, INFINITY), 0);
  EXPECT_EQ(std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(double)), 0);
  double loaded = 0.0;
  for (double v : fa) loaded = std::max(loaded, std::abs(v));
  EXPECT_GT(loaded, 0.0);
  // every bond broken through set_alive leaves no force at all: each lookup found its bond
  for (std::size_t b = 0; b < bi.size(); ++b) one_law.set_alive(bi[b], bj[b], false);
  std::vector<double> f0(2 * n, 0.0);
  one_law.add_forces(team, x.data(), f0.data(), fixed, cut2, INFINITY);
  double largest = 0.0;
  for (double v : f0) largest = std::max(largest, std::abs(v));
  EXPECT_EQ(largest, 0.0);
}
