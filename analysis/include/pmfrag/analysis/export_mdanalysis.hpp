// A copy of a run's frames that MDAnalysis opens as it is: RUN_DIR/mdanalysis/trajectory.h5md, H5MD 1.1 in
// units MDAnalysis knows. `mda.Universe("RUN/mdanalysis/trajectory.h5md")` needs no topology and no options.
#pragma once

#include <string>

namespace pmfrag::analysis {

struct MdanalysisExportOptions {
  long every = 1;  ///< write every K-th frame (the last frame always)
};

struct MdanalysisExportResult {
  std::string path;  ///< the file written
  long frames_read = 0, frames_written = 0;
  bool partial = false;  ///< the source trajectory was damaged or cut short; `note` says how
  std::string note;
};

/// Writes RUN_DIR/mdanalysis/trajectory.h5md from RUN_DIR/trajectory.h5. Positions are in Angstrom (cm x 1e8)
/// and velocities in Angstrom ps-1 (cm/s x 1e-4), MDAnalysis' own units, so it scales no coordinate on reading;
/// times stay in s. Each particle has 3 components (z = 0 for a 2-D run, whose box then says dimension 3 with a
/// "none" boundary, as MDAnalysis requires). The particle group is named "trajectory", where MDAnalysis looks
/// for the atom count, and holds the per-particle species and mass. MDAnalysis holds positions as 32-bit
/// floats, so a coordinate x comes back rounded once, by at most 2^-24 |x| (6e-8 |x|). The file is written to a
/// temporary name and renamed, so it is whole or absent; a partial source is marked in /parameters/partial.
MdanalysisExportResult export_mdanalysis(const std::string& run_dir, const MdanalysisExportOptions& options);

}  // namespace pmfrag::analysis
