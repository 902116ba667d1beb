// Trajectories in H5MD 1.1 (HDF5): /h5md metadata, /particles/all/{position,velocity} as time series with
// step and time, time-independent species (phase), id, mass and box, /connectivity/bonds (the original
// neighbour pairs), /observables, and /parameters (the scene text and the scalars of the run).
// Every frame is flushed, so a killed run leaves a file readable up to its last frame.
#pragma once

#include "pmfrag/effects.hpp"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pmfrag {

struct RunParameters {
  double dt = 0.0;        ///< s
  double dt_limit = 0.0;  ///< s, Eq. (15)
  double end = 0.0;       ///< s
  long frame_every = 1;   ///< steps between frames (0 with adaptive steps: frames are every output.every s)
  bool adaptive = false;  ///< dt = "adaptive" (dt is then the cap)
};

class H5mdWriter {
 public:
  /// Creates `path` (truncating it) and writes everything time-independent.
  H5mdWriter(const std::string& path, const System& sys, const Scene& scene, const RunParameters& run);
  /// Reopens an existing trajectory to append, keeping its first `keep_frames` frames (resume).
  H5mdWriter(const std::string& path, long keep_frames);
  ~H5mdWriter();
  H5mdWriter(const H5mdWriter&) = delete;
  H5mdWriter& operator=(const H5mdWriter&) = delete;

  /// Appends one frame: positions r_k and whole-step velocities v_k (N x dim, row-major), and observables.
  void write_frame(long step, double time, const std::vector<double>& position, const std::vector<double>& velocity,
                   const Observables& obs);
  long frames() const { return frames_; }
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long frames_ = 0;
};

/// A frame read back (for tests, analysis, resume).
struct TrajectoryFrame {
  long step = 0;
  double time = 0.0;
  std::vector<double> position, velocity;  ///< N x dim
};

/// Reads a trajectory, including a damaged one: a file cut short (a copy that stopped, a full disk) is read
/// from a zero-padded temporary copy, and only the leading frames whose data lie wholly before the cut are
/// offered; a frame whose bytes were altered fails its Fletcher-32 checksum when read (frame() throws).
/// damage() says what was found ("" for an intact file).
class H5mdReader {
 public:
  explicit H5mdReader(const std::string& path);
  ~H5mdReader();
  H5mdReader(const H5mdReader&) = delete;
  H5mdReader& operator=(const H5mdReader&) = delete;
  const std::string& damage() const { return damage_; }
  int dim() const { return dim_; }
  std::size_t particles() const { return n_; }
  long frames() const { return frames_; }
  TrajectoryFrame frame(long index) const;
  /// Times of the frames [s] (cheap: no particle data is read).
  std::vector<double> times() const;
  std::vector<std::array<int, 2>> bonds() const;
  std::vector<int> species() const;
  std::vector<double> mass() const;
  /// Observable time series by name (kinetic_energy, potential_energy, total_energy, boundary_work, ...).
  std::vector<double> observable(const std::string& name) const;
  double parameter(const std::string& name) const;
  /// The distinct pair laws and, for phases a, b, the index of their law at [a * nphase + b].
  std::vector<PairLaw> laws() const;
  std::vector<int> phase_pair_law() const;
  std::string scene_text() const;

 private:
  long long file_ = -1;
  int dim_ = 2;
  std::size_t n_ = 0;
  long frames_ = 0;
  std::string damage_, padded_copy_;
};

/// Everything needed to continue a run bitwise: the step, r_k, v_k-1/2, the effects' history and how many
/// frames the trajectory had at that step.
struct Checkpoint {
  long step = 0;
  double time = 0.0, dt = 0.0;  ///< s: time of the step, and the step that led to it
  int level = 0, calm = 0;      ///< adaptive steps: StepLevels history
  long frames = 0;
  std::vector<double> position, velocity, effects;
};
/// Written to `path`.tmp and renamed, so a checkpoint on disk is always complete.
void write_checkpoint(const std::string& path, const Checkpoint& c);
Checkpoint read_checkpoint(const std::string& path);

}  // namespace pmfrag
