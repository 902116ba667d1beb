// Fragments from a trajectory: the connected components of the intact bonds (the original neighbour pairs).
// Which bonds are broken at a frame comes from the engine's record in the trajectory (every bond it broke, at
// the step it broke), or, for trajectories without one or when asked, from the bond lengths at the frames.
// Streams frame by frame: memory is a few frames whatever the trajectory's length.
#pragma once

#include "pmfrag/analysis/crack.hpp"
#include "pmfrag/analysis/power_law.hpp"
#include "pmfrag/io/h5md.hpp"

#include <Eigen/Core>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace pmfrag::analysis {

/// When a bond counts as broken: longer than D (the interaction distance, default), than the damage
/// spacing r_d, or than factor x r0.
struct BreakCriterion {
  enum class Kind { cutoff, damage, factor };
  Kind kind = Kind::cutoff;
  double factor = 1.7;
  /// Parses "D", "rd" or a number (factor x r0); throws std::invalid_argument otherwise.
  static BreakCriterion parse(const std::string& text);
  /// "" (the default: the engine's record) gives none; anything else as parse().
  static std::optional<BreakCriterion> parse_option(const std::string& text);
  std::string describe() const;
};

struct TimelineRow {
  long step = 0;
  double time = 0.0;
  long broken = 0;
  long broken_engine = -1;  ///< the engine's own count at this frame (pairs_beyond_cutoff); -1 if absent
  long fragments = 0, fragments_2plus = 0, fragments_1pct = 0;
  double largest_fraction = 0.0, mean_mass = 0.0;
  double kinetic = 0.0, potential = 0.0;
  CrackExtent crack;  ///< tips and tip-to-tip extent of the broken bonds (crack.hpp)
};

struct Fragment {
  long id = 0;
  long particles = 0;
  double mass = 0.0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero(), velocity = Eigen::Vector3d::Zero();
  double radius_of_gyration = 0.0;
  Eigen::Vector3d principal = Eigen::Vector3d::Zero();  ///< principal radii (sqrt of gyration eigenvalues), descending
};

struct FragmentReport {
  int p = 0, q = 0;
  std::string bond_state;     ///< "recorded" (the engine's record) or "distance" (bond lengths at frames)
  double threshold_cm = 0.0;  ///< the distance reading's break length (recorded: D, where the engine broke them)
  std::string criterion;
  std::vector<TimelineRow> timeline;
  std::vector<Fragment> final_fragments;  ///< sorted by mass, largest first
  double total_mass = 0.0;       ///< g, of the bodies analysed (not of targets held in place)
  long particles = 0;            ///< in the bodies analysed
  long target_particles = 0;     ///< in bodies held in place entirely, left out
  double second_largest_fraction = 0.0;  ///< of the total mass, at the last frame (0 if one piece)
  /// n(m) ~ m^-tau of the final fragments (power_law.hpp); none, with the reason in distribution_note, when
  /// too few fragments exist or the particles differ in mass
  std::optional<PowerLawFit> distribution;
  double particle_mass = 0.0;  ///< g, when every particle has the same mass (0 otherwise)
  std::string distribution_note;
  double onset_time = -1.0;       ///< first frame with a broken bond (s)
  double separation_time = -1.0;  ///< first frame with >= 2 fragments each >= 5 % of the mass (s)
  long frames_read = 0;
  bool partial = false;  ///< the trajectory ended early or a frame could not be read
  std::string note;
};

/// Per-particle fragment labels of one frame, for export: fragment id (0 = largest) and its size.
struct FrameLabels {
  std::vector<int> fragment_id, fragment_size;
  std::vector<double> damage;  ///< fraction of each particle's original bonds broken
};

/// Which original bonds are broken at each frame, read in one of two ways:
///  recorded - the engine's record replayed up to the frame's step: exactly the bonds the simulation broke
///             (cutoff model: the pairs beyond D then; a pair that came back within D is intact again);
///  distance - a bond breaks the first time it is longer than a length at a frame, and stays broken (what
///             happened between frames is not seen: a bond that broke and closed again counts as intact).
class BondStates {
 public:
  /// The distance reading.
  BondStates(std::vector<std::array<int, 2>> bonds, int dim, double threshold_cm);
  /// The recorded reading, over `bonds` bonds.
  BondStates(std::size_t bonds, BondRecord record);
  /// The reading for a trajectory: by distance if `distance` is given, else its record, else (a trajectory
  /// without one, written by an older pmfrag) by distance at D.
  static BondStates open(const H5mdReader& trajectory, const std::optional<BreakCriterion>& distance);

  /// Whether frame k's bond state is known (a record cut short does not reach the last frames).
  bool covers(long frame) const;
  /// Advances to frame k with its positions (N x dim); frames in ascending order, each covered.
  void advance(long frame, const std::vector<double>& position);
  const std::vector<std::uint8_t>& broken() const { return broken_; }
  long broken_count() const { return count_; }
  bool recorded() const { return record_.has_value(); }
  std::string source() const { return recorded() ? "recorded" : "distance"; }
  /// What a broken bond is here, in words.
  const std::string& describe() const { return describe_; }
  double threshold_cm() const { return threshold_; }
  /// What is missing of the record ("" if whole, or for the distance reading).
  std::string damage() const { return record_ ? record_->damage : std::string(); }

 private:
  std::vector<std::array<int, 2>> bonds_;
  int dim_ = 2;
  double threshold_ = 0.0;
  std::optional<BondRecord> record_;
  std::size_t applied_ = 0;  ///< recorded: rows replayed so far
  std::vector<std::uint8_t> broken_;
  long count_ = 0;
  std::string describe_;
};

/// Labels fragments from a set of broken bonds.
class FragmentTracker {
 public:
  FragmentTracker(std::size_t particles, std::vector<std::array<int, 2>> bonds, std::vector<double> mass);
  /// The fragments when `broken` (one flag per bond) are broken.
  FrameLabels label(const std::vector<std::uint8_t>& broken) const;

 private:
  std::size_t n_;
  std::vector<std::array<int, 2>> bonds_;
  std::vector<double> mass_;
};

/// What makes everything read from this trajectory partial before any frame is read: damage to the file, and
/// a run that stopped or was interrupted short of its end ("" if neither).
std::string trajectory_caveats(const H5mdReader& trajectory);

/// Per particle, 1 if it belongs to a target: a body every particle of which a kinematic selection moves (a
/// wall or plate held in place). Targets are boundaries, not material under study: the statistics leave them
/// out and pictures draw them grey.
std::vector<std::uint8_t> target_particles(const H5mdReader& trajectory);
/// What a picture of the run is titled: the scene's `title = "..."` (else `fallback`), and on a second line the
/// --set overrides that ran, since a title quoting "200 cm/s" is wrong once --set changed the speed.
std::string run_title(const H5mdReader& trajectory, const std::string& fallback);
/// Appends `more` to a note, "; "-separated.
void add_note(std::string& note, const std::string& more);

/// The bond length [cm] beyond which a bond of this trajectory counts as broken.
double break_length(const H5mdReader& trajectory, const BreakCriterion& criterion);

/// Reads RUN_DIR/trajectory.h5 and analyses every frame whose bond state is known: from the engine's record,
/// or by distance if `distance` is given (or the trajectory has no record).
FragmentReport analyse_fragments(const std::string& trajectory, const std::optional<BreakCriterion>& distance);

/// Writes fragments_timeline.csv, fragments_final.csv, fragment_sizes.csv (log-binned n(m)),
/// fragment_mass_ccdf.csv (the cumulative distribution) and summary.json into dir
/// (each written whole under a temporary name, then renamed).
void write_fragment_report(const FragmentReport& report, const std::string& dir);

}  // namespace pmfrag::analysis
