// Fragments: union-find, clustering of intact bonds, irreversible breakage, reports from a real run.
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/analysis/particle_fields.hpp"
#include "pmfrag/analysis/union_find.hpp"
#include "pmfrag/run/run.hpp"
#include "pmfrag/body/system.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>
#include <random>
#include <set>

using namespace pmfrag;
using namespace pmfrag::analysis;

TEST(UnionFind, HandBuiltGraphs) {
  UnionFind uf(7);
  uf.unite(0, 1), uf.unite(1, 2), uf.unite(4, 5);
  EXPECT_EQ(uf.find(0), uf.find(2));
  EXPECT_NE(uf.find(0), uf.find(4));
  EXPECT_EQ(uf.size_of(2), 3u);
  EXPECT_EQ(uf.size_of(5), 2u);
  EXPECT_EQ(uf.size_of(6), 1u);
  uf.unite(2, 5);
  EXPECT_EQ(uf.size_of(4), 5u);
  uf.unite(0, 4);  // already joined: no change
  EXPECT_EQ(uf.size_of(1), 5u);
  // a long chain
  UnionFind chain(1000);
  for (std::size_t i = 0; i + 1 < 1000; ++i) chain.unite(i, i + 1);
  EXPECT_EQ(chain.size_of(999), 1000u);
}

TEST(Fragments, BreakageIsIrreversibleAndLabelsAreByMass) {
  // Four particles in a row, bonds 0-1, 1-2, 2-3, r0 = 1.
  std::vector<std::array<int, 2>> bonds{{0, 1}, {1, 2}, {2, 3}};
  BondStates t(bonds, 2, 1.5);
  const FragmentTracker labels(4, bonds, {1.0, 1.0, 1.0, 1.0});
  t.advance(0, {0, 0, 1, 0, 2, 0, 3, 0});
  auto l = labels.label(t.broken());
  EXPECT_EQ(t.broken_count(), 0);
  EXPECT_EQ(std::set<int>(l.fragment_id.begin(), l.fragment_id.end()).size(), 1u);
  t.advance(1, {0, 0, 1, 0, 2, 0, 4.6, 0});  // bond 2-3 stretched to 2.6 > 1.5: breaks
  l = labels.label(t.broken());
  EXPECT_EQ(t.broken_count(), 1);
  EXPECT_EQ(l.fragment_id[0], 0);  // the three-particle piece is the largest: id 0
  EXPECT_EQ(l.fragment_id[3], 1);
  EXPECT_EQ(l.fragment_size[0], 3);
  EXPECT_EQ(l.fragment_size[3], 1);
  EXPECT_DOUBLE_EQ(l.damage[3], 1.0);
  EXPECT_DOUBLE_EQ(l.damage[2], 0.5);
  t.advance(2, {0, 0, 1, 0, 2, 0, 3, 0});  // back at r0: stays broken
  l = labels.label(t.broken());
  EXPECT_EQ(t.broken_count(), 1);
  EXPECT_EQ(l.fragment_size[3], 1);
}

TEST(Fragments, PlateCutAlongALineGivesTwoPiecesWithTheRightMasses) {
  const std::string text = R"(
[[body]]
lattice = "triangular"
shape = { kind = "rect", min = [0, 0], max = [4, 4] }
slits = [ { from = [-1, 2.05], to = [5, 2.05] } ]
[[phase]]
p = 7
q = 14
[pair]
[time]
dt = 1e-7
end = 1e-6
)";
  const Scene sc = parse_scene(text, "cut.toml");
  const System sys = build_system(sc);
  long above = 0;
  for (const auto& x : sys.position) above += x.y() > 2.05;
  const auto dir = test::temp_dir("cut");
  RunOptions ro;
  ro.out_dir = dir.string();
  ASSERT_TRUE(run_scene(sc, ro).completed);
  const auto rep = analyse_fragments((dir / "trajectory.h5").string(), std::nullopt);
  EXPECT_EQ(rep.bond_state, "recorded");
  ASSERT_EQ(rep.final_fragments.size(), 2u);
  const double m = sys.phase_mass[0];
  const long below = static_cast<long>(sys.size()) - above;
  EXPECT_NEAR(rep.final_fragments[0].mass, m * std::max(above, below), 1e-12);
  EXPECT_NEAR(rep.final_fragments[1].mass, m * std::min(above, below), 1e-12);
  EXPECT_EQ(rep.timeline.back().broken, 0);  // cut bonds never existed: nothing "broke"
  EXPECT_GT(rep.separation_time, -1.0);      // two pieces of >= 5 % from the first frame
  write_fragment_report(rep, dir.string());
  for (const char* f : {"fragments_timeline.csv", "fragments_final.csv", "fragment_sizes.csv", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::ifstream js(dir / "summary.json");
  const std::string s((std::istreambuf_iterator<char>(js)), std::istreambuf_iterator<char>());
  EXPECT_NE(s.find("\"fragments\": 2"), std::string::npos) << s;
  std::filesystem::remove_all(dir);
}

TEST(Fragments, CriterionParsing) {
  EXPECT_EQ(BreakCriterion::parse("D").kind, BreakCriterion::Kind::cutoff);
  EXPECT_EQ(BreakCriterion::parse("rd").kind, BreakCriterion::Kind::damage);
  EXPECT_DOUBLE_EQ(BreakCriterion::parse("1.5").factor, 1.5);
  EXPECT_THROW(BreakCriterion::parse("0.5"), std::invalid_argument);
  EXPECT_THROW(BreakCriterion::parse("x"), std::invalid_argument);
}

TEST(Crack, TipsAreTheEndsOfTheBrokenBondsAlongTheirLine) {
  // A row of 6 particles above a row of 6 below (spacing 1); the vertical bonds 1..4 are broken: the crack
  // runs from x = 1 to x = 4 at y = 0.5 (midpoints in the initial configuration).
  std::vector<double> x0;
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i < 6; ++i) x0.insert(x0.end(), {static_cast<double>(i), static_cast<double>(row)});
  std::vector<std::array<int, 2>> bonds;
  std::vector<std::uint8_t> broken;
  for (int i = 0; i < 6; ++i) bonds.push_back({i, i + 6}), broken.push_back(i >= 1 && i <= 4);
  const auto c = analysis::crack_extent(x0, 2, bonds, broken);
  ASSERT_TRUE(c.present);
  EXPECT_NEAR(c.tip_a.x(), 1.0, 1e-12);
  EXPECT_NEAR(c.tip_b.x(), 4.0, 1e-12);
  EXPECT_NEAR(c.tip_a.y(), 0.5, 1e-12);
  EXPECT_NEAR(c.extent_cm, 3.0, 1e-12);
  broken.assign(6, 0);
  broken[2] = 1;
  EXPECT_FALSE(analysis::crack_extent(x0, 2, bonds, broken).present) << "one broken bond is not yet a crack";
}

TEST(PowerLaw, HurwitzZetaMatchesKnownValues) {
  EXPECT_NEAR(hurwitz_zeta(2.0, 1.0), std::numbers::pi * std::numbers::pi / 6.0, 1e-13);
  EXPECT_NEAR(hurwitz_zeta(2.0, 2.0), std::numbers::pi * std::numbers::pi / 6.0 - 1.0, 1e-13);
  EXPECT_NEAR(hurwitz_zeta(3.0, 1.0), 1.2020569031595942, 1e-13);
  EXPECT_NEAR(hurwitz_zeta(1.5, 1.0), 2.6123753486854883, 1e-12);
  EXPECT_NEAR(hurwitz_zeta(4.0, 1.0), std::pow(std::numbers::pi, 4) / 90.0, 1e-13);
}

namespace {
// Exact draws from P(s) = s^-tau / zeta(tau, s_min), s >= s_min: the s with P(S >= s) >= u > P(S >= s + 1).
std::vector<long> power_law_sample(double tau, long s_min, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double z = hurwitz_zeta(tau, static_cast<double>(s_min));
  const auto tail = [&](long s) { return hurwitz_zeta(tau, static_cast<double>(s)) / z; };
  std::vector<long> out;
  for (std::size_t k = 0; k < n; ++k) {
    const double u = 1.0 - u01(rng);  // (0, 1]
    long lo = s_min;
    while (tail(2 * lo) >= u) lo *= 2;
    long hi = 2 * lo;  // tail(lo) >= u > tail(hi)
    while (hi - lo > 1) {
      const long mid = lo + (hi - lo) / 2;
      (tail(mid) >= u ? lo : hi) = mid;
    }
    out.push_back(lo);
  }
  return out;
}
}  // namespace

TEST(PowerLaw, MaximumLikelihoodRecoversAKnownExponentWithinItsInterval) {
  // 600 fragments drawn from a discrete power law above 2 particles (plus singles and small pieces below a
  // bend, which the rule for s_min must leave out), for the exponents fragmentation reports (1 to 2.6).
  for (const double tau : {1.5, 2.0, 2.6}) {
    int covered = 0;
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      auto sizes = power_law_sample(tau, 4, 600, seed);
      for (int k = 0; k < 200; ++k) sizes.push_back(1 + k % 3);  // 1-3 particles, far too many for the law
      std::string why;
      const auto fit = fit_discrete_power_law(sizes, why);
      ASSERT_TRUE(fit) << why;
      EXPECT_NEAR(fit->exponent, tau, 0.3) << "seed " << seed;  // s_min chosen from the data adds spread
      EXPECT_GE(fit->s_min, 4) << "the excess below 4 particles must be cut off";
      EXPECT_LT(fit->ci_low, fit->exponent);
      EXPECT_GT(fit->ci_high, fit->exponent);
      covered += fit->ci_low <= tau && tau <= fit->ci_high;
    }
    std::printf("tau = %.1f: the 95 %% interval covers it in %d of 10 samples\n", tau, covered);
    EXPECT_GE(covered, 8) << "tau " << tau;
  }
}

TEST(PowerLaw, TooFewFragmentsGiveNoExponentAndSayWhy) {
  std::string why;
  EXPECT_FALSE(fit_discrete_power_law({2, 3, 5, 2, 8, 13, 2, 4, 1, 1, 1, 1}, why));
  EXPECT_NE(why.find("at least 10"), std::string::npos) << why;
  EXPECT_TRUE(fit_discrete_power_law(power_law_sample(2.0, 2, 10, 7), why)) << why;
}

TEST(ParticleFields, ValuesTheirUnitsAndUnknownNames) {
  // Two particles in 2-D: one moved by (3, 4) cm at (6, 8) cm/s, one still.
  TrajectoryFrame first, now;
  first.position = {0.0, 0.0, 1.0, 0.0};
  first.velocity = {0.0, 0.0, 0.0, 0.0};
  now.position = {3.0, 4.0, 1.0, 0.0};
  now.velocity = {6.0, 8.0, 0.0, 0.0};
  analysis::FrameLabels labels;
  labels.fragment_id = {0, 1};
  labels.fragment_size = {1, 1};
  labels.damage = {1.0, 0.5};
  const std::vector<int> species{0, 1};
  const std::vector<double> mass{2.0, 3.0};
  const analysis::FieldFrame at{now, first, labels, species, mass, 2};
  EXPECT_EQ(analysis::particle_field("displacement", at), (std::vector<double>{5.0, 0.0}));     // cm
  EXPECT_EQ(analysis::particle_field("speed", at), (std::vector<double>{10.0, 0.0}));           // cm/s
  EXPECT_EQ(analysis::particle_field("kinetic_energy", at), (std::vector<double>{100.0, 0.0}));  // erg
  EXPECT_EQ(analysis::particle_field("phase", at), (std::vector<double>{0.0, 1.0}));
  EXPECT_EQ(analysis::particle_field("fragment_id", at), (std::vector<double>{0.0, 1.0}));
  EXPECT_EQ(analysis::particle_field("damage", at), (std::vector<double>{1.0, 0.5}));
  for (const auto& name : analysis::particle_field_names()) EXPECT_EQ(analysis::particle_field(name, at).size(), 2u) << name;
  EXPECT_THROW(analysis::particle_field("stress", at), std::invalid_argument);
}
