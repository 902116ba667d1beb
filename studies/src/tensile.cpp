#include "pmfrag/studies/tensile.hpp"

#include "pmfrag/io/h5md.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/run/run.hpp"
#include "pmfrag/body/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag::studies {

namespace {

// Width of the middle slab (initial y within r0/2 of the centre) along axis a.
double middle_width(const std::vector<double>& x, const std::vector<double>& x0, int dim, double yc, double r0, int a) {
  double lo = INFINITY, hi = -INFINITY;
  const std::size_t d = static_cast<std::size_t>(dim), n = x.size() / d;
  for (std::size_t i = 0; i < n; ++i)
    if (std::fabs(x0[i * d + 1] - yc) < 0.5 * r0)
      lo = std::min(lo, x[i * d + static_cast<std::size_t>(a)]), hi = std::max(hi, x[i * d + static_cast<std::size_t>(a)]);
  return hi - lo;
}

}  // namespace

TensileResult tensile_test(const std::filesystem::path& dir, int dim, int p, int q, int scale) {
  const double r0 = 0.2, v = 20.0, strain = 2e-3;
  // 2-D: 6 x 12 cm triangular plate; 3-D: 16 x 30 x 12 fcc sites; both times `scale`. Height twice the width,
  // so the clamped rows (which cannot contract sideways) disturb little of the block.
  char text[2000];
  const int sx = 16 * scale, sy = 30 * scale, sz = 12 * scale;  // 3-D sites
  const double width = 6.0 * scale, height = dim == 2 ? 12.0 * scale : (sy - 1) * r0 * std::sqrt(3.0) / 2.0;
  const double t_end = strain * height / (2.0 * v);
  if (dim == 2)
    std::snprintf(text, sizeof text,
                  "[[body]]\nlattice = \"triangular\"\nr0 = %g\nshape = { kind = \"rect\", min = [0.0, 0.0], max = [%g, %g] }\n"
                  "[[phase]]\np = %d\nq = %d\nblock = [8.0, 11.43, 3.1]\n[pair]\n"
                  "[[kinematic]]\nselect = { row = \"top\" }\nvelocity = [0.0, %g]\n"
                  "[[kinematic]]\nselect = { row = \"bottom\" }\nvelocity = [0.0, %g]\n"
                  "[time]\ndt = \"auto\"\nend = %.9g\n[output]\nevery = %.9g\n",
                  r0, width, height, p, q, v, -v, t_end, t_end / 40);
  else
    std::snprintf(text, sizeof text,
                  "[[body]]\nlattice = \"fcc\"\nr0 = %g\norigin = [0.0, 0.0, 0.0]\nsites = [%d, %d, %d]\n"
                  "[[phase]]\np = %d\nq = %d\nblock = [8.0, 11.43, 3.1]\n[pair]\n"
                  "[[kinematic]]\nselect = { row = \"top\" }\nvelocity = [0.0, %g, 0.0]\n"
                  "[[kinematic]]\nselect = { row = \"bottom\" }\nvelocity = [0.0, %g, 0.0]\n"
                  "[time]\ndt = \"auto\"\nend = %.9g\n[output]\nevery = %.9g\n",
                  r0, sx, sy, sz, p, q, v, -v, t_end, t_end / 40);
  const std::filesystem::path run_dir = dir / ((dim == 2 ? "2d_p" : "3d_p") + std::to_string(p) + "_q" + std::to_string(q));
  const Scene sc = parse_scene(text, (run_dir / "scene.toml").string());
  RunOptions ro;
  ro.out_dir = run_dir.string();
  ro.force = true;
  const RunResult rr = run_scene(sc, ro);
  if (!rr.completed) throw std::runtime_error(run_dir.string() + ": run stopped: " + rr.message);

  H5mdReader rd((run_dir / "trajectory.h5").string());
  const auto U = rd.observable("potential_energy"), t = rd.times();
  const TrajectoryFrame f0 = rd.frame(0), f1 = rd.frame(rd.frames() - 1);
  const std::size_t n = rd.particles(), d = static_cast<std::size_t>(dim);
  double ymin = INFINITY, ymax = -INFINITY;
  for (std::size_t i = 0; i < n; ++i) ymin = std::min(ymin, f0.position[i * d + 1]), ymax = std::max(ymax, f0.position[i * d + 1]);
  const double L0 = ymax - ymin;
  // Volume of the lattice: per particle sqrt(3)/2 r0^2 x a thickness of r0 (2-D), r0^3 / sqrt(2) (close packing).
  const double V = static_cast<double>(n) * (dim == 2 ? std::sqrt(3.0) / 2.0 * r0 * r0 * r0 : r0 * r0 * r0 / std::sqrt(2.0));
  // Least squares of U - U0 = (E V / 2) eps^2 through the origin.
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < U.size(); ++k) {
    const double e = 2 * v * t[k] / L0, x = e * e;
    sxy += x * (U[k] - U[0]), sxx += x * x;
  }
  const double slope = sxy / sxx;
  double res2 = 0, u2 = 0;
  for (std::size_t k = 0; k < U.size(); ++k) {
    const double e = 2 * v * t[k] / L0;
    res2 += std::pow(U[k] - U[0] - slope * e * e, 2), u2 += std::pow(U[k] - U[0], 2);
  }
  TensileResult r;
  r.dim = dim, r.p = p, r.q = q, r.particles = n;
  r.E_eq26 = derive_material(p, q, r0).E_GPa;
  r.E_fit = 2 * slope / V * 1e-10;
  r.strain = 2 * v * t.back() / L0;
  r.fit_rms = std::sqrt(res2 / u2);
  const double yc = 0.5 * (ymin + ymax);
  const double w0 = middle_width(f0.position, f0.position, dim, yc, r0, 0);
  const double w1 = middle_width(f1.position, f0.position, dim, yc, r0, 0);
  r.poisson = -((w1 - w0) / w0) / r.strain;
  return r;
}

}  // namespace pmfrag::studies
