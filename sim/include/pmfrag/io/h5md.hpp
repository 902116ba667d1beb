// Trajectories in H5MD 1.1 (HDF5): /h5md metadata, /particles/all/{position,velocity} as time series with
// step and time, time-independent species (phase), id, mass and box, /connectivity/bonds (the original
// neighbour pairs), /connectivity/broken_bonds (the engine's record of every bond it broke: an event table,
// README "Trajectories"), /observables, and /parameters (the scene text and the scalars of the run).
// Every frame is flushed, so a killed run leaves a file readable up to its last frame.
#pragma once

#include "pmfrag/step/effects.hpp"

#include <functional>
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
  /// Reopens an existing trajectory to append, keeping its first `keep_frames` frames and `keep_events` rows
  /// of the bond record (resume).
  H5mdWriter(const std::string& path, long keep_frames, long keep_events);
  ~H5mdWriter();
  H5mdWriter(const H5mdWriter&) = delete;
  H5mdWriter& operator=(const H5mdWriter&) = delete;

  /// Appends one frame: positions r_k and whole-step velocities v_k (N x dim, row-major), and observables.
  /// With it, the number of bond-record rows written so far (every event up to this step: append them first).
  void write_frame(long step, double time, const std::vector<double>& position, const std::vector<double>& velocity,
                   const Observables& obs);
  /// The same from N x dim arrays in place (the integrator's own, no copy); `velocity` is not read when the
  /// frames leave velocities out (writes_velocity()).
  void write_frame(long step, double time, const double* position, const double* velocity, const Observables& obs);
  /// Rows [first, first + count) of an N x dim frame, written into out (count x dim).
  using FrameRows = std::function<void(std::size_t first, std::size_t count, double* out)>;
  /// The same with the velocities made a chunk at a time (no N x dim array of them).
  void write_frame(long step, double time, const double* position, const FrameRows& velocity, const Observables& obs);
  bool writes_velocity() const;
  /// Appends rows to the bond record (/connectivity/broken_bonds), in step order; on disk at the next flush.
  void append_bond_events(const std::vector<BondEvent>& events);
  /// Writes everything appended so far to disk (write_frame does it too).
  void flush();
  /// Records that the run ended before its end time, and why (/parameters/incomplete); a resume removes it.
  void mark_incomplete(const std::string& why);
  long frames() const { return frames_; }
  long bond_event_rows() const { return events_; }
  void close();

 private:
  void create(const System& sys, const Scene& scene, const RunParameters& run);
  void append_frame(long step, double time, const double* position, const FrameRows& velocity, const Observables& obs);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long frames_ = 0, events_ = 0;
};

/// HDF5's own error stack, printed to stderr beside pmfrag's one-line messages when `shown` (`pmfrag
/// --verbose`); off by default.
void show_library_diagnostics(bool shown);

/// The engine's record of bond events read back: the rows that lie wholly before any damage, and for each
/// frame how many rows belong to it and the frames before (rows_at_frame[k]: the events of steps up to frame
/// k's). A frame whose rows are not all readable (a record cut short) has no entry: rows_at_frame is then
/// shorter than the frames, and damage() says why.
struct BondRecord {
  std::string model;  ///< "bonded" or "cutoff" (what the events mean: effects.hpp, BondEvent)
  std::vector<BondEvent> events;
  std::vector<long> rows_at_frame;
  std::string damage;  ///< "" if whole
};

/// A frame read back (for tests, analysis, resume).
struct TrajectoryFrame {
  long step = 0;
  double time = 0.0;
  std::vector<double> position, velocity;  ///< N x dim; velocity empty if the run left it out (output.fields)
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
  const std::string& path() const { return path_; }
  int dim() const { return dim_; }
  std::size_t particles() const { return n_; }
  long frames() const { return frames_; }
  /// Whether frames hold velocities (a scene's `output.fields = ["position"]` leaves them out).
  bool has_velocity() const { return has_velocity_; }
  TrajectoryFrame frame(long index) const;
  /// The same, into `into`'s buffers (a reader going through frames of millions of particles reuses them).
  void frame(long index, TrajectoryFrame& into) const;
  /// Times of the frames [s] (cheap: no particle data is read).
  std::vector<double> times() const;
  std::vector<std::array<int, 2>> bonds() const;
  /// Whether the trajectory holds the engine's record of bond events (older trajectories do not).
  bool has_bond_record() const;
  /// The record, checked: rows in step order naming bonds of /connectivity/bonds, each a change of state
  /// (throws std::runtime_error naming the file and dataset otherwise).
  BondRecord bond_record() const;
  std::vector<int> species() const;
  std::vector<double> mass() const;
  std::vector<int> body() const;
  /// 1 for particles a kinematic selection moves (0 for all in trajectories written before it was recorded).
  std::vector<int> held() const;
  /// Observable time series by name (kinetic_energy, potential_energy, total_energy, boundary_work, ...).
  std::vector<double> observable(const std::string& name) const;
  double parameter(const std::string& name) const;
  /// The distinct pair laws and, for phases a, b, the index of their law at [a * nphase + b].
  std::vector<PairLaw> laws() const;
  std::vector<int> phase_pair_law() const;
  std::string scene_text() const;
  /// The `--set KEY=VALUE` overrides the run was made with, in order (none in trajectories without the record).
  std::vector<std::string> overrides() const;
  /// Why the run ended before its end time ("" if it did not, or has been resumed to the end).
  std::string incomplete() const;

 private:
  long long file_ = -1;
  std::string path_;
  unsigned long long limit_ = 0;  ///< bytes before the cut of a truncated file (0: whole)
  int dim_ = 2;
  std::size_t n_ = 0;
  long frames_ = 0;
  bool has_velocity_ = true;
  std::string damage_, padded_copy_;
};

/// Everything needed to continue a run bitwise: the step, r_k, v_k-1/2, the effects' history and how many
/// frames the trajectory had at that step.
struct Checkpoint {
  long step = 0;
  double time = 0.0, dt = 0.0;  ///< s: time of the step, and the step that led to it
  int level = 0, calm = 0;      ///< adaptive steps: StepLevels history
  long frames = 0;
  long bond_events = 0;  ///< rows of the trajectory's bond record at that step
  std::vector<double> position, velocity, effects;
};
/// Written to `path`.tmp and renamed, so a checkpoint on disk is always complete.
void write_checkpoint(const std::string& path, const Checkpoint& c);
/// The same with the positions and velocities (`values` doubles each) read in place, not from c's vectors
/// (a run at millions of particles makes no copy of its state to checkpoint it).
void write_checkpoint(const std::string& path, const Checkpoint& c, const double* position, const double* velocity,
                      std::size_t values);
Checkpoint read_checkpoint(const std::string& path);

/// A cut trajectory holds fewer whole frames (or bond-record rows) than its checkpoint counts.
struct TrajectoryShortOfCheckpoint : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Resume after a full disk or a killed writer: HDF5 cannot reopen for appending a trajectory whose end the disk
/// cut off, and one whose writer died between flushes may hold half of a frame's metadata. Its first
/// `keep_frames` frames and `keep_events` rows of the bond record (what the checkpoint counts), read back from
/// the cut file, are written into a new trajectory (the time-independent data from sys, scene and run, as a new
/// run writes them), which then replaces it. Throws TrajectoryShortOfCheckpoint, naming the file and what is
/// missing, if the cut file does not hold them whole; the cut file is then left as it was.
void rebuild_trajectory(const std::string& path, const System& sys, const Scene& scene, const RunParameters& run,
                        long keep_frames, long keep_events);
/// Whether `path` may be appended to: its writer closed it (it left no PATH.writing beside it), and HDF5 opens it
/// for writing (not a trajectory cut short).
bool trajectory_opens_for_append(const std::string& path);

}  // namespace pmfrag
