// Hard cases stay numerically stable (label `hard`): the stiff law near the stability limit, impacts with
// adaptive steps, the logarithmic and the softest laws, pieces flying apart, degenerate bodies.
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/step/neighbors.hpp"
#include "pmfrag/run/run.hpp"
#include "pmfrag/body/system.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace pmfrag;

namespace {

// Random velocities on a free body (no boundaries), for energy checks with nothing pumping energy in.
System free_body(Scene& sc, double speed, unsigned seed) {
  sc.kinematic.clear();
  System sys = build_system(sc);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, speed);
  for (auto& v : sys.velocity) v = Vec3(gauss(rng), gauss(rng), 0.0);
  return sys;
}

// Energy error of a run, relative to the initial kinetic energy, sampled every `every` steps: the secular
// drift (least-squares slope x duration) and the largest excursion. Leapfrog does not conserve E exactly but
// a nearby "shadow" energy, so E fluctuates by about (omega dt)^2/4 of the energy in each mode, which is
// large for the highest modes near the limit; what must stay small is the drift.
struct EnergyError {
  double drift = INFINITY, excursion = INFINITY;
};
EnergyError energy_error(Leapfrog<2>& lf, long steps, long every) {
  const Observables o0 = lf.observe();
  const double e0 = o0.kinetic + o0.potential;
  double st = 0, se = 0, stt = 0, ste = 0, worst = 0, n = 0;
  for (long k = 1; k <= steps; ++k) {
    lf.step();
    if (k % every == 0) {
      const Observables o = lf.observe();
      const double e = o.kinetic + o.potential - e0, t = static_cast<double>(k);
      if (!std::isfinite(e)) return {};
      st += t, se += e, stt += t * t, ste += t * e, n += 1, worst = std::max(worst, std::fabs(e));
    }
  }
  const double slope = (n * ste - st * se) / (n * stt - st * st);
  return {std::fabs(slope * static_cast<double>(steps)) / o0.kinetic, worst / o0.kinetic};
}

// A --set item "key=value" with the value at full precision.
std::string set_number(const std::string& key, double value) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", value);
  return key + "=" + b;
}

// The stability limit of the paper's (7,14) plate [s].
double plate_714_limit() {
  const Scene probe = read_scene(test::case_path("slit_plate_7_14.toml"));
  return choose_step(probe, build_system(probe)).limit;
}

double min_distance(const std::vector<double>& x, int dim) {
  const std::size_t n = x.size() / static_cast<std::size_t>(dim);
  double best = INFINITY;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      double r2 = 0.0;
      for (int d = 0; d < dim; ++d) r2 += std::pow(x[i * dim + d] - x[j * dim + d], 2);
      best = std::min(best, r2);
    }
  return std::sqrt(best);
}

}  // namespace

TEST(Hard, StiffLawAtNineTenthsOfTheLimitKeepsItsEnergyFor1e5Steps) {
  Scene sc = read_scene(test::case_path("slit_plate_7_14.toml"));
  System sys = free_body(sc, 100.0, 7);
  const StepChoice c = choose_step(sc, sys);
  EXPECT_NEAR(c.lattice_factor, 1.0 / std::sqrt(6.0), 0.01) << "triangular lattice: omega_max^2 = 6 k/m";
  auto lf = test::make_leapfrog<2>(sys, sc, 0.9 * c.limit);
  const EnergyError err = energy_error(lf, test::scaled(100000), 50);
  std::printf("(7,14) free plate at 0.9 x limit (%.4g s), %ld steps: drift %.3g, excursion %.3g of KE0\n",
              0.9 * c.limit, test::scaled(100000), err.drift, err.excursion);
  // Random velocities put a share of KE0 into the highest modes, where 0.9 x the limit means omega dt = 1.8:
  // measured drift 5.3e-3 and excursion 0.55 of KE0 (the pulled plate below, the paper's loading: 1e-8 of
  // the work). At the paper's dt = 1e-7 s (0.3 x) Dynamics.FreePlate... holds the drift under 1e-4.
  EXPECT_LT(err.drift, 1e-2);
  EXPECT_LT(err.excursion, 1.0);
}

TEST(Hard, LatticeFactorOfTheFccBlockIsItsHighestFrequency) {
  // Nearest-neighbour springs on an fcc lattice: Omega_max^2 = 8 k/m, so the limit is Eq. 15 x 1/sqrt(8)
  // (0.3536), less the 1 % margin on the frequency squared (0.3518). The paper's 54,940-particle block: its
  // free faces soften it a little, and the Lanczos iteration stops just short of lambda_max, both of which
  // raise the factor (measured 0.3524; the triangular plate is checked in the test above).
  const Scene sc = read_scene(test::case_path("block3d_slit.toml"));
  const StepChoice c = choose_step(sc, build_system(sc));
  EXPECT_NEAR(c.lattice_factor, 1.0 / std::sqrt(8.0 * 1.01), 0.002);
  EXPECT_GE(c.lattice_factor, 1.0 / std::sqrt(8.0 * 1.01) - 1e-4) << "the body is no stiffer than the bulk";
}

TEST(Hard, StiffPulledPlateAtNineTenthsOfTheLimitBalancesEnergyUntilItBreaks) {
  // The paper's loading (rows pulled at 20 cm/s) excites no high modes: the balance kinetic + potential -
  // boundary work holds far better than on the free plate. After the first bond breaks, pairs pressed below
  // r0 are stiffer than the limit assumes and a fixed step of 0.9 x the limit is stopped by the guard
  // (docs/stability.md); here the run ends just before.
  Scene sc = read_scene(test::case_path("slit_plate_7_14.toml"),
                        {set_number("time.dt", 0.9 * plate_714_limit()), set_number("time.end", 1.04e-2 * test::test_scale())});
  RunOptions ro;
  ro.out_dir = test::temp_dir("pulled09").string();
  const RunResult r = run_scene(sc, ro);
  ASSERT_TRUE(r.completed) << r.message;
  H5mdReader rd(ro.out_dir + "/trajectory.h5");
  const auto bal = rd.observable("energy_balance"), work = rd.observable("boundary_work");
  double worst = 0.0;
  for (std::size_t k = 0; k < bal.size(); ++k) worst = std::max(worst, std::fabs(bal[k] - bal[0]));
  std::printf("(7,14) pulled plate at 0.9 x limit, %ld steps: |balance error| / work = %.3g\n", r.steps, worst / work.back());
  EXPECT_GT(r.steps, test::scaled(30000));
  EXPECT_LT(worst, 1e-6 * work.back());
}

TEST(Hard, AboveTheLimitIsRefusedAndForcedThroughTheGuardStopsIt) {
  Scene sc = read_scene(test::case_path("slit_plate_7_14.toml"),
                        {set_number("time.dt", 1.1 * plate_714_limit()), "time.end=1e-3", "output.every=1e-6"});
  RunOptions ro;
  ro.out_dir = test::temp_dir("above").string();
  EXPECT_THROW((void)run_scene(sc, ro), UnstableStepError);
  ro.allow_unstable = true;
  const RunResult r = run_scene(sc, ro);
  EXPECT_FALSE(r.completed);
  EXPECT_NE(r.message.find("unstable: particle "), std::string::npos) << r.message;
  H5mdReader rd(ro.out_dir + "/trajectory.h5");
  ASSERT_EQ(rd.frames(), r.frames);
  for (long k = 0; k < rd.frames(); ++k)
    for (double x : rd.frame(k).position) ASSERT_TRUE(std::isfinite(x)) << "frame " << k;
}

class Impact : public ::testing::TestWithParam<double> {};

TEST_P(Impact, AdaptiveStepsKeepEnergyAndDistance) {
  const double speed = GetParam();
  char vel[64];
  std::snprintf(vel, sizeof vel, "impactor.0.velocity=[0.0, %.1f]", -speed);
  // The paper's clamp r_min = 0.1 r0: a fixed step would have to be 1e-9 s (Eq. 15 at r_min). The disc
  // starts 0.04 cm clear of contact, so even the shortened (sanitizer) run sees the impact.
  const std::string end = set_number("time.end", std::max(3e-3, 6e-3 * test::test_scale()));
  Scene sc = read_scene(test::case_path("impact.toml"), {vel, "time.dt=\"adaptive\"", "pair.r_min=0.1", end,
                                                        "output.every=2e-5", "body.1.shape.center=[0.0, 1.0]"});
  const System sys = build_system(sc);
  const std::size_t plate = static_cast<std::size_t>(std::count(sys.body.begin(), sys.body.end(), 0));
  RunOptions ro;
  ro.out_dir = test::temp_dir("impact").string();
  const RunResult r = run_scene(sc, ro);
  ASSERT_TRUE(r.completed) << r.message;
  H5mdReader rd(ro.out_dir + "/trajectory.h5");
  const auto ke = rd.observable("kinetic_energy"), bal = rd.observable("energy_balance");
  double drift = 0.0, closest = INFINITY;
  for (std::size_t k = 0; k < ke.size(); ++k) {
    ASSERT_TRUE(std::isfinite(bal[k]));
    drift = std::max(drift, std::fabs(bal[k] - bal[0]));
  }
  double contact = INFINITY;  // closest disc-plate pair
  for (long k = 0; k < rd.frames(); ++k) {
    const auto f = rd.frame(k);
    for (double x : f.position) ASSERT_TRUE(std::isfinite(x));
    closest = std::min(closest, min_distance(f.position, 2));
    for (std::size_t i = 0; i < plate; ++i)
      for (std::size_t j = plate; j < f.position.size() / 2; ++j)
        contact = std::min(contact, std::hypot(f.position[2 * i] - f.position[2 * j],
                                               f.position[2 * i + 1] - f.position[2 * j + 1]));
  }
  std::printf("impact %g cm/s: %ld steps, smallest step %.3g s, |balance drift| / KE0 = %.3g, closest %.4f cm, "
              "disc-plate %.4f cm\n", speed, r.steps, r.dt_min, drift / ke[0], closest, contact);
  EXPECT_LT(contact, 0.2) << "the disc must press into the plate (closer than r0) within the run";
  EXPECT_LT(drift, 0.01 * ke[0]);
  EXPECT_GT(closest, 0.5 * 0.1 * 0.2) << "no pair closer than r_min / 2";
}
INSTANTIATE_TEST_SUITE_P(Speeds, Impact, ::testing::Values(50.0, 200.0, 1000.0),
                         [](const auto& i) { return "v" + std::to_string(static_cast<int>(i.param)); });

class SoftLaws : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(SoftLaws, RunAndKeepTheirEnergy) {
  const auto [p, q] = GetParam();
  Scene sc = read_scene(test::case_path("slit_plate_3_5.toml"),
                        {"phase.0.p=" + std::to_string(p), "phase.0.q=" + std::to_string(q)});
  System sys = free_body(sc, 100.0, 11);
  const StepChoice c = choose_step(sc, sys);
  auto lf = test::make_leapfrog<2>(sys, sc, 0.5 * c.limit);
  const EnergyError err = energy_error(lf, test::scaled(20000), 10);
  std::printf("(%d,%d) at 0.5 x limit (%.4g s), %ld steps: drift %.3g, excursion %.3g of KE0\n", p, q, 0.5 * c.limit,
              test::scaled(20000), err.drift, err.excursion);
  EXPECT_LT(err.drift, 1e-3);
  EXPECT_LT(err.excursion, 0.2);
}
INSTANTIATE_TEST_SUITE_P(Laws, SoftLaws,
                         ::testing::Values(std::pair{1, 2}, std::pair{1, 3}, std::pair{1, 15}, std::pair{6, 7},
                                           std::pair{13, 14}),
                         [](const auto& i) {
                           return "p" + std::to_string(i.param.first) + "_q" + std::to_string(i.param.second);
                         });

TEST(Hard, PiecesFlyingApartCostNoMoreNeighbourWork) {
  // Two 20 x 20 patches, pulled apart from 1 cm to 1e5 cm: memory and pair checks stay those of one patch.
  std::vector<Eigen::Vector2d> x;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) x.emplace_back(0.2 * i + 0.1 * j, 0.17 * j);
  const std::size_t half = x.size();
  x.resize(2 * half);
  CellList<2> cells;
  std::size_t first_checks = 0, first_pairs = 0;
  for (double gap : {1e2, 1e3, 1e4, 1e5}) {
    for (std::size_t i = 0; i < half; ++i) x[half + i] = x[i] + Eigen::Vector2d(gap, 0.5 * gap);
    std::size_t pairs = 0;
    cells.for_each_pair(x, 0.5, [&](std::uint32_t, std::uint32_t, double) { ++pairs; });
    if (first_checks == 0) first_checks = cells.checks(), first_pairs = pairs;
    EXPECT_EQ(pairs, first_pairs) << "gap " << gap;
    EXPECT_LE(cells.checks(), first_checks) << "gap " << gap;
    EXPECT_LT(cells.checks(), 40 * x.size()) << "gap " << gap;
  }
}

TEST(Hard, DegenerateBodiesRunOrAreRefusedClearly) {
  auto scene = [](const std::string& shape, const std::string& extra = "") {
    return "[[body]]\nlattice = \"triangular\"\nshape = " + shape + "\n[[phase]]\np = 3\nq = 5\n" + extra +
           "[pair]\n[time]\ndt = 1e-7\nend = 1e-5\n[output]\nevery = 1e-6\n";
  };
  struct Case {
    std::string name, text;
    std::size_t particles;
  };
  const Case cases[] = {
      {"one particle", scene("{ kind = \"rect\", min = [0, 0], max = [0.05, 0.05] }"), 1},
      {"two particles", scene("{ kind = \"rect\", min = [0, 0], max = [0.25, 0.05] }"), 2},
      {"a single row", scene("{ kind = \"rect\", min = [0, 0], max = [4, 0.05] }"), 21},
  };
  for (const auto& c : cases) {
    const Scene sc = parse_scene(c.text, c.name + ".toml");
    const System sys = build_system(sc);
    EXPECT_EQ(sys.size(), c.particles) << c.name;
    RunOptions ro;
    ro.out_dir = test::temp_dir("degenerate").string();
    const RunResult r = run_scene(sc, ro);
    EXPECT_TRUE(r.completed) << c.name << ": " << r.message;
    H5mdReader rd(ro.out_dir + "/trajectory.h5");
    EXPECT_EQ(rd.frames(), 11) << c.name;
    for (double e : rd.observable("total_energy")) EXPECT_TRUE(std::isfinite(e)) << c.name;
  }
  // A phase whose region holds no particle is refused, naming it.
  const Scene empty = parse_scene(
      scene("{ kind = \"rect\", min = [0, 0], max = [2, 2] }",
            "[[phase]]\nname = \"ghost\"\np = 7\nq = 14\nregion = { kind = \"disc\", center = [50, 50], radius = 1 }\n"),
      "empty.toml");
  try {
    (void)build_system(empty);
    FAIL() << "an empty phase must be refused";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("ghost"), std::string::npos) << e.what();
  }
  // No body at all is a scene error too.
  EXPECT_THROW((void)parse_scene("[[phase]]\np = 3\nq = 5\n[pair]\n[time]\ndt = 1e-7\nend = 1e-5\n", "none.toml"),
               SceneError);
}

TEST(Hard, CutoffBlockBalancesEnergyAsPairsCrossD) {
  // A close-packed block under the cutoff model: its second shell (sqrt(2) r0) lies inside D = 1.7 r0 and
  // pulls the lattice in, and the third (sqrt(3) r0) sits at D, so pairs cross D all the time. Each crossing
  // would change the potential by phi(D); reported shifted to zero at D, kinetic + potential - boundary work
  // must hold to 1e-3 of the kinetic energy. The force still jumps at D, which leapfrog integrates to first
  // order in dt: the balance error falls about linearly with dt (docs/physics.md), and dt = 6.25e-9 s meets
  // 1e-3 (at 1e-7 s it is 4 % here).
  const std::string text = R"(
[[body]]
lattice = "fcc"
r0 = 0.2
origin = [0.0, 0.0, 0.0]
sites = [16, 24, 8]
[[phase]]
p = 7
q = 14
block = [8.0, 11.43, 3.1]
[pair]
model = "cutoff"
[[kinematic]]
select = { row = "top" }
velocity = [0.0, 20.0, 0.0]
[[kinematic]]
select = { row = "bottom" }
velocity = [0.0, -20.0, 0.0]
[time]
dt = 6.25e-9
[output]
every = 1e-5
)";
  const Scene sc = parse_scene(text, "cutoff_block.toml", {set_number("time.end", 1e-4 * test::test_scale())});
  RunOptions ro;
  ro.out_dir = test::temp_dir("cutoff_block").string();
  const RunResult r = run_scene(sc, ro);
  ASSERT_TRUE(r.completed) << r.message;
  H5mdReader rd(ro.out_dir + "/trajectory.h5");
  const auto bal = rd.observable("energy_balance"), ke = rd.observable("kinetic_energy");
  // How many pairs are within D at the first and the last frame: their change times phi(D) is what the
  // unshifted potential would have jumped by.
  const auto within = [&](long k) {
    const auto x = rd.frame(k).position;
    const double cut2 = std::pow(rd.parameter("cutoff"), 2);
    long n = 0;
    for (std::size_t i = 0; i < rd.particles(); ++i)
      for (std::size_t j = i + 1; j < rd.particles(); ++j) {
        double r2 = 0.0;
        for (int d = 0; d < 3; ++d) r2 += std::pow(x[i * 3 + d] - x[j * 3 + d], 2);
        n += r2 <= cut2;
      }
    return n;
  };
  const long crossed = std::labs(within(rd.frames() - 1) - within(0));
  const double jump = static_cast<double>(crossed) * std::fabs(rd.laws().front().potential(rd.parameter("cutoff")));
  double worst = 0.0;
  for (std::size_t k = 1; k < bal.size(); ++k) worst = std::max(worst, std::fabs(bal[k] - bal[0]) / ke[k]);
  std::printf("cutoff block, %ld steps of 6.25e-9 s: pairs within D changed by %ld (x phi(D) = %.3g of the final "
              "kinetic energy); |balance error| / kinetic energy <= %.3g\n",
              r.steps, crossed, jump / ke.back(), worst);
  EXPECT_GT(jump, 0.1 * ke.back()) << "the test needs pairs crossing D";
  EXPECT_LT(worst, 1e-3);
}
