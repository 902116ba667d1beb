// LAMMPS as the engine for runs beyond one machine: a scene written as a LAMMPS deck (`pmfrag lammps`), run
// with `mpirun -np N lmp -in in.lammps`, and read back into a pmfrag run folder (`pmfrag import`).
#pragma once

#include "pmfrag/body/scene.hpp"
#include "pmfrag/body/system.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag {

/// A scene needs an effect the deck cannot express in LAMMPS; what() names it.
struct LammpsUnsupported : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Throws LammpsUnsupported naming the first part of `scene` LAMMPS cannot run as pmfrag does.
void check_lammps_can_run(const Scene& scene, const System& sys);

/// The particles and bonds as a LAMMPS data file (atom_style bond, CGS): atom type 1 = free, 2, 3, ... = the
/// scene's [[kinematic]] selections in order; velocities at t = 0 (impactors); bond type 1.
void write_lammps_data(const std::filesystem::path& path, const Scene& scene, const System& sys);

struct LammpsDeck {
  long steps = 0;        ///< of dt each
  long frame_every = 0;  ///< steps between frames
  double dt = 0.0;       ///< s
  std::vector<std::string> files;  ///< written into the folder, in.lammps first
};

/// Writes `dir`/in.lammps with its data (data.lammps), the law's tables and, for `pmfrag import`, the scene
/// (scene.toml, overrides.txt) - a complete deck, runnable as `cd dir && lmp -in in.lammps`. The run writes
/// frames.dump (id, x, y, z, vx, vy, vz every frame_every steps, sorted by id), for the bonded reading
/// bonds.dump (the bonds still intact at each frame), and log.lammps. Bonded: the law tabulated as a bond that
/// breaks past D (fix bond/break every step), contacts within r0 through pair_style mie/cut; cutoff: pair_style
/// mie/cut to D. Throws LammpsUnsupported for what LAMMPS cannot express.
LammpsDeck write_lammps_deck(const Scene& scene, const System& sys, const std::filesystem::path& dir);

}  // namespace pmfrag

namespace pmfrag {

/// What `pmfrag import` read.
struct LammpsImport {
  long frames = 0;           ///< written to the trajectory
  long last_step = 0;        ///< of the last whole frame
  long steps = 0;            ///< the deck's run length
  bool partial = false;      ///< the run stopped short or its dump was cut: note says where
  std::string note;
  long bonds_broken = 0, bonds_re_formed = 0;
  double first_break_time = -1.0;  ///< s, the first frame that shows a broken bond (-1: none)
  double lammps_wall_s = 0.0;      ///< LAMMPS' "Loop time" (0 if its log is missing)
  int lammps_procs = 0;
};

/// Reads the run of a deck written by write_lammps_deck into the pmfrag run folder `out` (trajectory.h5,
/// scene.toml, overrides.txt, run.json), so that fragments, export and render read it as they read a pmfrag
/// run. The particles, bonds and laws are rebuilt from the deck's scene; positions and velocities come from
/// frames.dump; the bond record from bonds.dump (bonded: a bond missing from a frame broke since the previous
/// one) or from the frames' bond lengths against D (cutoff); kinetic energy from the velocities, potential
/// energy from log.lammps. Bond events are known to the frame, not the step: each is dated by the first frame
/// that shows it. A dump cut short is read up to its last whole frame and the run marked incomplete; a folder
/// that is not a deck, or a dump that does not match its particles, throws std::runtime_error naming the file
/// (and line).
LammpsImport import_lammps_run(const std::filesystem::path& deck, const std::filesystem::path& out, bool force);

}  // namespace pmfrag
