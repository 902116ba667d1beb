// Per-particle values of a frame, by name: what `pmfrag export` writes and `pmfrag render` colours by, computed
// in one place (no VTK here: the writers and the renderer take plain numbers).
#pragma once

#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/io/h5md.hpp"

#include <string>
#include <vector>

namespace pmfrag::analysis {

/// What a field may need of one frame. References: the caller keeps them alive.
struct FieldFrame {
  const TrajectoryFrame& frame;
  const TrajectoryFrame& first;    ///< the initial frame (displacements are from it)
  const FrameLabels& labels;       ///< fragments and damage at this frame
  const std::vector<int>& species;  ///< phase index per particle
  const std::vector<double>& mass;  ///< g
  int dim = 2;
};

/// The names particle_field() knows, with their units: id, phase, fragment_id, fragment_size (counts),
/// displacement (cm, the length of the displacement from the first frame), speed (cm/s), kinetic_energy (erg),
/// damage (the fraction of a particle's original bonds broken).
const std::vector<std::string>& particle_field_names();

/// One value per particle of the named field (std::invalid_argument for a name not listed above).
std::vector<double> particle_field(const std::string& name, const FieldFrame& at);

}  // namespace pmfrag::analysis
