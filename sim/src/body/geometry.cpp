#include "pmfrag/body/geometry.hpp"

#include <cmath>
#include <sstream>

namespace pmfrag {

namespace {
constexpr double tol = 1e-9;  // cm: geometry is given to ~1e-8 cm in the paper's tables
}

bool Region::contains(const Vec3& x) const {
  switch (kind) {
    case Kind::all: return true;
    case Kind::rect:
      return x.x() >= min.x() - tol && x.x() <= max.x() + tol && x.y() >= min.y() - tol && x.y() <= max.y() + tol;
    case Kind::box:
      return (x.array() >= min.array() - tol).all() && (x.array() <= max.array() + tol).all();
    case Kind::disc: return (x - center).head<2>().norm() <= radius + tol;
    case Kind::sphere: return (x - center).norm() <= radius + tol;
  }
  return false;
}

std::string Region::describe() const {
  std::ostringstream s;
  switch (kind) {
    case Kind::all: s << "all"; break;
    case Kind::rect: s << "rect (" << min.x() << ", " << min.y() << ")-(" << max.x() << ", " << max.y() << ")"; break;
    case Kind::box:
      s << "box (" << min.x() << ", " << min.y() << ", " << min.z() << ")-(" << max.x() << ", " << max.y() << ", "
        << max.z() << ")";
      break;
    case Kind::disc: s << "disc at (" << center.x() << ", " << center.y() << ") r = " << radius << " cm"; break;
    case Kind::sphere:
      s << "sphere at (" << center.x() << ", " << center.y() << ", " << center.z() << ") r = " << radius << " cm";
      break;
  }
  return s.str();
}

bool Segment::crossed_by(const Vec3& a, const Vec3& b) const {
  // Orientation tests in the xy plane.
  auto cross = [](double ux, double uy, double vx, double vy) { return ux * vy - uy * vx; };
  const double px = from.x(), py = from.y(), rx = to.x() - px, ry = to.y() - py;
  const double qx = a.x(), qy = a.y(), sx = b.x() - qx, sy = b.y() - qy;
  const double denom = cross(rx, ry, sx, sy);
  if (std::fabs(denom) < 1e-300) return false;  // parallel: a bond along the cut is not cut by it
  const double t = cross(qx - px, qy - py, sx, sy) / denom;
  const double u = cross(qx - px, qy - py, rx, ry) / denom;
  return t >= 0.0 && t <= 1.0 && u >= 0.0 && u <= 1.0;
}

}  // namespace pmfrag
