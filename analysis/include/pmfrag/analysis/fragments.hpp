// Fragments from a trajectory: bonds (the original neighbour pairs) break the first time they are longer
// than a criterion and stay broken; fragments are the connected components of the intact bonds.
// Streams frame by frame: memory is a few frames whatever the trajectory's length.
#pragma once

#include "pmfrag/analysis/crack.hpp"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace pmfrag {
class H5mdReader;
}

namespace pmfrag::analysis {

/// When a bond counts as broken: longer than D (the interaction distance, default), than the damage
/// spacing r_d, or than factor x r0.
struct BreakCriterion {
  enum class Kind { cutoff, damage, factor };
  Kind kind = Kind::cutoff;
  double factor = 1.7;
  /// Parses "D", "rd" or a number (factor x r0); throws std::invalid_argument otherwise.
  static BreakCriterion parse(const std::string& text);
  std::string describe() const;
};

struct TimelineRow {
  long step = 0;
  double time = 0.0;
  long broken = 0;
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
  double threshold_cm = 0.0;
  std::string criterion;
  std::vector<TimelineRow> timeline;
  std::vector<Fragment> final_fragments;  ///< sorted by mass, largest first
  double total_mass = 0.0;
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

class FragmentTracker {
 public:
  FragmentTracker(std::size_t particles, std::vector<std::array<int, 2>> bonds, std::vector<double> mass, int dim,
                  double threshold_cm);
  /// Advances the break state with one frame's positions (N x dim); returns the labels of that frame.
  FrameLabels update(const std::vector<double>& position);
  const std::vector<std::uint8_t>& broken() const { return broken_; }
  long broken_count() const { return count_; }

 private:
  std::size_t n_;
  std::vector<std::array<int, 2>> bonds_;
  std::vector<double> mass_;
  int dim_;
  double threshold2_;
  std::vector<std::uint8_t> broken_;
  long count_ = 0;
};

/// The bond length [cm] beyond which a bond of this trajectory counts as broken.
double break_length(const H5mdReader& trajectory, const BreakCriterion& criterion);

/// Reads RUN_DIR/trajectory.h5 and analyses every frame.
FragmentReport analyse_fragments(const std::string& trajectory, const BreakCriterion& criterion);

/// Writes fragments_timeline.csv, fragments_final.csv, fragment_sizes.csv and summary.json into dir
/// (each written whole under a temporary name, then renamed).
void write_fragment_report(const FragmentReport& report, const std::string& dir);

}  // namespace pmfrag::analysis
