#include "pmfrag/analysis/crack.hpp"

#include <Eigen/Eigenvalues>

#include <limits>

namespace pmfrag::analysis {

CrackExtent crack_extent(const std::vector<double>& x0, int dim, const std::vector<std::array<int, 2>>& bonds,
                         const std::vector<std::uint8_t>& broken) {
  CrackExtent c;
  std::vector<Eigen::Vector3d> mid;
  for (std::size_t b = 0; b < bonds.size() && b < broken.size(); ++b) {
    if (!broken[b]) continue;
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (int d = 0; d < dim; ++d)
      m[d] = 0.5 * (x0[static_cast<std::size_t>(bonds[b][0]) * dim + d] + x0[static_cast<std::size_t>(bonds[b][1]) * dim + d]);
    mid.push_back(m);
  }
  if (mid.size() < 2) return c;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& m : mid) mean += m;
  mean /= static_cast<double>(mid.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& m : mid) cov += (m - mean) * (m - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);  // largest eigenvalue last
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& m : mid) {
    const double s = (m - mean).dot(axis);
    if (s < lo) lo = s, c.tip_a = m;
    if (s > hi) hi = s, c.tip_b = m;
  }
  if (c.tip_b.x() < c.tip_a.x()) std::swap(c.tip_a, c.tip_b);
  c.present = true;
  c.extent_cm = (c.tip_b - c.tip_a).norm();
  return c;
}

}  // namespace pmfrag::analysis
