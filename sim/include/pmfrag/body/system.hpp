// The System: particles, their phases and original bonds, and the pair laws between phases — plain data
// built from a Scene, separate from the simulation that advances it (cf. OpenMM's System vs Context).
#pragma once

#include "pmfrag/body/scene.hpp"

#include <array>
#include <string>
#include <vector>

namespace pmfrag {

struct System {
  int dim = 2;
  double r0 = 0.2;      ///< cm
  double cutoff = 0.34; ///< D [cm]
  double r_min = 0.0;   ///< cm; force held constant inside (0 = no clamp)
  std::vector<Vec3> position;  ///< cm (z = 0 in 2-D)
  std::vector<Vec3> velocity;  ///< cm/s at t = 0
  std::vector<int> phase;      ///< index into phase_names
  std::vector<int> body;       ///< index into body_names
  std::vector<int> site;       ///< the site's number in its lattice's storage order (Greenspan's i)
  std::vector<std::string> phase_names, body_names;
  std::vector<double> phase_mass;         ///< g
  std::vector<PairLaw> laws;              ///< distinct laws
  std::vector<int> phase_pair_law;        ///< [a * nphase + b] -> index into laws
  std::vector<std::array<int, 2>> bonds;  ///< original nearest-neighbour pairs (i < j), same body, sorted
  std::vector<int> held;                  ///< 1 for particles a kinematic selection moves (targets, pulled rows)

  std::size_t size() const { return position.size(); }
  const PairLaw& law(int phase_a, int phase_b) const {
    return laws[static_cast<std::size_t>(phase_pair_law[static_cast<std::size_t>(phase_a) * phase_names.size() + phase_b])];
  }
};

/// Builds particles, phases, laws and bonds. Throws SceneError for selections or bodies that come out empty,
/// overlapping particles, and similar problems a user can act on.
System build_system(const Scene& scene);

/// Indices of the particles a selection picks (sorted). Throws SceneError if it picks none.
std::vector<int> select_particles(const System& sys, const Selection& sel, const std::string& what);

/// Eq. (15) limit for the system: the smallest over phase pairs, with dF/dr at r0 (stretch) or at r_min when
/// the scene clamps the force there (impact).
/// `at_r_min = false` gives the stretch limit even when an r_min is set.
/// Eq. (15) is a single pair's limit, 2/omega with omega^2 = k/m. A particle in a lattice is held by all its
/// neighbours, so the body's highest frequency is higher: for the triangular lattice omega_max^2 = 6 k/m, and
/// the leapfrog limit is Eq. 15 / sqrt(6) = 0.41 x Eq. 15 (measured: the (7,14) plate is stable at 0.40 x Eq. 15
/// and blows up at 0.45 x). The limit used is therefore Eq. 15 times lattice_factor(sys).
double system_dt_limit(const System& sys, bool at_r_min = true);

/// Eq. (15) for a single pair: what the paper prints.
double pair_dt_limit(const System& sys, bool at_r_min = true);

/// The leapfrog limit of the body at rest, 2/sqrt(lambda_max(M^-1 K)) with K the stiffness of the original
/// bonds at their initial lengths, by Lanczos iteration; infinite if there are no bonds.
double lattice_dt_limit(const System& sys);

/// lattice_dt_limit / pair_dt_limit(stretch), at most 1 (0.408 for the triangular lattice).
double lattice_factor(const System& sys);

/// The step a scene asks for: dt in seconds, "auto" (safety x the limit) or "adaptive" (dt is then the cap:
/// time.dt_max, or safety x the stretch limit). `limit` is the Eq. 15 limit of system_dt_limit.
struct StepChoice {
  double dt = 0.0, limit = 0.0;
  double pair_limit = 0.0;      ///< s: Eq. 15 as the paper prints it
  double lattice_factor = 1.0;  ///< limit / pair_limit
  bool adaptive = false;
};
StepChoice choose_step(const Scene& scene, const System& sys);

}  // namespace pmfrag
