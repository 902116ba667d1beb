// Regions and segments used by scenes to shape bodies, place phases and select particles.
#pragma once

#include <Eigen/Core>

#include <string>

namespace pmfrag {

using Vec3 = Eigen::Vector3d;

/// A region of space. 2-D scenes use rect and disc (z ignored); 3-D scenes use box and sphere.
struct Region {
  enum class Kind { all, rect, box, disc, sphere };
  Kind kind = Kind::all;
  Vec3 min = Vec3::Zero(), max = Vec3::Zero();  // rect, box
  Vec3 center = Vec3::Zero();                   // disc, sphere
  double radius = 0.0;                          // disc, sphere

  /// Points on the boundary count as inside (within a relative tolerance), so a rectangle drawn through
  /// lattice sites keeps them.
  bool contains(const Vec3& x) const;
  /// A short description for messages, e.g. "disc at (0, 0) r = 1 cm".
  std::string describe() const;
};

/// A straight cut (2-D): bonds whose xy projection crosses it are removed. In 3-D it cuts through the
/// whole thickness (an extruded segment).
struct Segment {
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  /// True if the segment a-b crosses this one in the xy plane (touching an end counts).
  bool crossed_by(const Vec3& a, const Vec3& b) const;
};

}  // namespace pmfrag
