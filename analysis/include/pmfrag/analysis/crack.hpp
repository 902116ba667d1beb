// Where the crack is: the broken bonds' midpoints, placed in the initial configuration (so the path is not
// blurred by how far the faces have opened), and its two tips, the extreme midpoints along the principal
// direction of the set. The tip-to-tip extent is the crack's length for one straight crack; for a crack grown
// from both ends of a slit it spans the slit too, and branches or edge cracks widen it.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace pmfrag::analysis {

struct CrackExtent {
  bool present = false;  ///< at least two broken bonds
  Eigen::Vector3d tip_a = Eigen::Vector3d::Zero(), tip_b = Eigen::Vector3d::Zero();  ///< cm; tip_a has the smaller x
  double extent_cm = 0.0;
};

/// `x0`: initial positions (N x dim); `broken`: one flag per bond.
CrackExtent crack_extent(const std::vector<double>& x0, int dim, const std::vector<std::array<int, 2>>& bonds,
                         const std::vector<std::uint8_t>& broken);

}  // namespace pmfrag::analysis
