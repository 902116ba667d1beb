// ParaView particle sets: RUN_DIR/vtk/frame_NNNNN.vtu (particles as vertices, bonds as lines, with fields)
// and RUN_DIR/particles.pvd (a collection whose timestep is the simulated time in seconds).
#pragma once

#include "pmfrag/analysis/fragments.hpp"

#include <set>
#include <string>

namespace pmfrag::analysis {

/// How the appended binary data of each .vtu is compressed. LZ4 is the default: on the 3-D block it writes
/// 4.5x faster than zlib level 1 for 30 % more bytes; ParaView (VTK >= 8) reads all three.
enum class Compression { lz4, zlib, none };

struct ExportOptions {
  long every = 1;                ///< write every K-th frame (the last frame always)
  std::set<std::string> fields;  ///< point/cell arrays to write; empty = all
  /// when a bond counts as broken (fragments, damage, `broken`): none = the engine's record (BondStates)
  std::optional<BreakCriterion> criterion;
  Compression compression = Compression::lz4;
};

struct ExportResult {
  long frames_read = 0, frames_written = 0;
  bool partial = false;
  std::string note;
};

/// The names of every field export can write.
const std::set<std::string>& export_fields();

ExportResult export_vtk(const std::string& run_dir, const ExportOptions& options);

}  // namespace pmfrag::analysis
