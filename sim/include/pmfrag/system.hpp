// The System: particles, their phases and original bonds, and the pair laws between phases — plain data
// built from a Scene, separate from the simulation that advances it (cf. OpenMM's System vs Context).
#pragma once

#include "pmfrag/scene.hpp"

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
  std::vector<std::array<int, 2>> bonds;  ///< original nearest-neighbour pairs (i < j), same body

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
double system_dt_limit(const System& sys);

}  // namespace pmfrag
