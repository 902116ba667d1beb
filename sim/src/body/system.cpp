#include "pmfrag/body/system.hpp"

#include "pmfrag/step/neighbors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>

namespace pmfrag {

namespace {

Sites generate_sites(const BodySpec& b, int dim) {
  if (b.lattice == LatticeKind::greenspan_plate) return greenspan_plate();
  Vec3 origin;
  int nx = 1, ny = 1, nz = 1;
  if (b.sites) {
    origin = *b.origin;
    nx = (*b.sites)[0];
    ny = (*b.sites)[1];
    nz = dim == 3 ? (*b.sites)[2] : 1;
  } else {
    Vec3 lo, hi;
    if (b.shape.kind == Region::Kind::disc || b.shape.kind == Region::Kind::sphere) {
      lo = b.shape.center - Vec3::Constant(b.shape.radius);
      hi = b.shape.center + Vec3::Constant(b.shape.radius);
    } else {
      lo = b.shape.min;
      hi = b.shape.max;
    }
    if (dim == 2) lo.z() = hi.z() = 0.0;
    origin = b.origin ? *b.origin : lo;
    lattice_counts_for(origin, hi, b.r0, dim, nx, ny, nz);
  }
  if (static_cast<double>(nx) * ny * nz > 5e7) throw SceneError("body '" + b.name + "': more than 5e7 lattice sites");
  if (dim == 2) return triangular_lattice(b.r0, origin, nx, ny);
  return close_packed_lattice(b.r0, origin, nx, ny, nz, b.lattice == LatticeKind::fcc ? Stacking::fcc : Stacking::hcp);
}

int phase_index(const Scene& sc, const std::string& name) {
  for (std::size_t i = 0; i < sc.phases.size(); ++i)
    if (sc.phases[i].name == name) return static_cast<int>(i);
  throw SceneError(sc.file + ": no phase named '" + name + "'");
}

}  // namespace

System build_system(const Scene& sc) {
  System sys;
  sys.dim = sc.dim;
  sys.r0 = sc.bodies.front().r0;
  const PairSpec pair = sc.pair.value_or(PairSpec{});
  sys.cutoff = pair.cutoff_r0 * sys.r0;
  sys.r_min = pair.r_min_r0 * sys.r0;

  // Phases: derive or take each law and mass.
  for (const auto& ph : sc.phases) {
    sys.phase_names.push_back(ph.name);
    if (ph.derived) {
      const Material m = derive_material(ph.p, ph.q, sys.r0, ph.block);
      sys.laws.push_back(m.law);
      sys.phase_mass.push_back(m.mass_g);
    } else {
      sys.laws.push_back(PairLaw{ph.p, ph.q, ph.G, ph.H});
      sys.phase_mass.push_back(ph.mass);
    }
  }
  const std::size_t np = sc.phases.size();
  sys.phase_pair_law.assign(np * np, -1);
  for (std::size_t a = 0; a < np; ++a) sys.phase_pair_law[a * np + a] = static_cast<int>(a);
  for (const auto& in : sc.interfaces) {
    const int a = phase_index(sc, in.a), b = phase_index(sc, in.b);
    PairLaw law;
    if (in.explicit_law) {
      law = in.law;
    } else {  // the weaker of the two (smaller peak force), scaled
      const PairLaw& la = sys.laws[static_cast<std::size_t>(a)];
      const PairLaw& lb = sys.laws[static_cast<std::size_t>(b)];
      law = la.peak_force() <= lb.peak_force() ? la : lb;
      law.G *= in.scale;
      law.H *= in.scale;
    }
    sys.laws.push_back(law);
    const int idx = static_cast<int>(sys.laws.size() - 1);
    sys.phase_pair_law[static_cast<std::size_t>(a) * np + b] = idx;
    sys.phase_pair_law[static_cast<std::size_t>(b) * np + a] = idx;
  }
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b)
      if (sys.phase_pair_law[a * np + b] < 0) {  // undeclared interface: the weaker phase law
        const PairLaw& la = sys.laws[a];
        const PairLaw& lb = sys.laws[b];
        sys.laws.push_back(la.peak_force() <= lb.peak_force() ? la : lb);
        sys.phase_pair_law[a * np + b] = sys.phase_pair_law[b * np + a] = static_cast<int>(sys.laws.size() - 1);
      }

  // Bodies: sites, shape, holes, voids; then phases by region.
  std::vector<std::size_t> body_begin;
  for (std::size_t bi = 0; bi < sc.bodies.size(); ++bi) {
    const BodySpec& b = sc.bodies[bi];
    sys.body_names.push_back(b.name);
    body_begin.push_back(sys.size());
    const Sites sites = generate_sites(b, sc.dim);
    const std::set<int> voids(b.void_sites.begin(), b.void_sites.end());
    for (int v : voids)
      if (v < 1 || v > static_cast<int>(sites.position.size()))
        throw SceneError(sc.file + ": body '" + b.name + "': void site " + std::to_string(v) + " is not in 1.." +
                         std::to_string(sites.position.size()));
    const int body_phase = phase_index(sc, b.phase);
    for (std::size_t s = 0; s < sites.position.size(); ++s) {
      const Vec3& x = sites.position[s];
      if (voids.count(sites.index[s])) continue;
      if (!b.shape.contains(x)) continue;
      bool in_hole = false;
      for (const auto& h : b.holes) in_hole = in_hole || h.contains(x);
      if (in_hole) continue;
      sys.position.push_back(x);
      sys.velocity.push_back(Vec3::Zero());
      sys.phase.push_back(body_phase);
      sys.body.push_back(static_cast<int>(bi));
      sys.site.push_back(sites.index[s]);
    }
    if (sys.size() == body_begin.back())
      throw SceneError(sc.file + ": body '" + b.name + "' has no particles (shape, holes and voids remove every site)");
  }
  // Growth by doubling left up to twice the particles' bytes until the run frees them.
  sys.position.shrink_to_fit(), sys.velocity.shrink_to_fit(), sys.phase.shrink_to_fit();
  sys.body.shrink_to_fit(), sys.site.shrink_to_fit();
  for (std::size_t p = 0; p < sc.phases.size(); ++p) {
    if (!sc.phases[p].region) continue;
    std::size_t count = 0;
    for (std::size_t i = 0; i < sys.size(); ++i)
      if (sc.phases[p].region->contains(sys.position[i])) sys.phase[i] = static_cast<int>(p), ++count;
    if (count == 0)
      throw SceneError(sc.file + ": phase '" + sc.phases[p].name + "': region " + sc.phases[p].region->describe() +
                       " selects no particle");
  }

  // Original bonds: nearest neighbours (second shell is at sqrt(2) r0 or more) of the same body, minus
  // those crossing a slit. Also refuse overlapping particles.
  CellList<3> cells;
  const double bond_reach = 1.2 * sys.r0;
  cells.for_each_pair(sys.position, bond_reach, [&](std::uint32_t i, std::uint32_t j, double r2) {
    if (sys.body[i] != sys.body[j]) {
      // Two bodies closer than a lattice allows (a target placed across the body that strikes it) would start
      // with contact forces of the stiffest part of the law.
      if (r2 < 0.64 * sys.r0 * sys.r0)
        throw SceneError(sc.file + ": bodies '" + sys.body_names[static_cast<std::size_t>(sys.body[i])] + "' and '" +
                         sys.body_names[static_cast<std::size_t>(sys.body[j])] + "' overlap at t = 0: particles " +
                         std::to_string(i) + " and " + std::to_string(j) + " are " + std::to_string(std::sqrt(r2)) +
                         " cm apart (less than 0.8 r0 = " + std::to_string(0.8 * sys.r0) + " cm); move one of them");
      return;
    }
    if (r2 < 0.25 * sys.r0 * sys.r0)
      throw SceneError(sc.file + ": particles " + std::to_string(i) + " and " + std::to_string(j) + " overlap (" +
                       std::to_string(std::sqrt(r2)) + " cm apart, r0 = " + std::to_string(sys.r0) + " cm)");
    const auto& slits = sc.bodies[static_cast<std::size_t>(sys.body[i])].slits;
    for (const auto& s : slits)
      if (s.crossed_by(sys.position[i], sys.position[j])) return;
    sys.bonds.push_back({static_cast<int>(i), static_cast<int>(j)});
  });
  std::sort(sys.bonds.begin(), sys.bonds.end());
  sys.bonds.shrink_to_fit();  // growth by doubling left up to twice the bonds' bytes for the whole run

  // Initial velocities of impactors.
  for (const auto& im : sc.impactors) {
    const auto idx = select_particles(sys, Selection{Selection::Kind::body, {}, im.body}, "impactor");
    for (int i : idx) sys.velocity[static_cast<std::size_t>(i)] = im.velocity;
  }
  // Particles a kinematic selection will move (the effect is built from the same selection).
  sys.held.assign(sys.size(), 0);
  for (std::size_t k = 0; k < sc.kinematic.size(); ++k)
    for (int i : select_particles(sys, sc.kinematic[k].select, "kinematic[" + std::to_string(k) + "].select"))
      sys.held[static_cast<std::size_t>(i)] = 1;
  return sys;
}

std::vector<int> select_particles(const System& sys, const Selection& sel, const std::string& what) {
  std::vector<int> out;
  const std::size_t n = sys.size();
  if (sel.kind == Selection::Kind::top_row || sel.kind == Selection::Kind::bottom_row) {
    double ext = sel.kind == Selection::Kind::top_row ? -INFINITY : INFINITY;
    for (const auto& x : sys.position) ext = sel.kind == Selection::Kind::top_row ? std::max(ext, x.y()) : std::min(ext, x.y());
    // 2-D: rows are r0 sin60 = 0.87 r0 apart, so a quarter of r0 takes one row. 3-D: close-packed layers are
    // shifted by a third of that in y (fcc: 0, 0.29 and 0.58 r0; hcp: 0 and 0.29 r0), so the face is the
    // outermost row of every layer: 0.7 r0 takes them all and none of the next rows (0.87 r0 and beyond).
    // A narrower band pulled one layer in three and tore it out of the block.
    const double band = (sys.dim == 3 ? 0.7 : 0.25) * sys.r0;
    for (std::size_t i = 0; i < n; ++i)
      if (std::fabs(sys.position[i].y() - ext) < band) out.push_back(static_cast<int>(i));
  } else {
    int name_index = -1;
    if (sel.kind == Selection::Kind::phase || sel.kind == Selection::Kind::body) {
      const auto& names = sel.kind == Selection::Kind::phase ? sys.phase_names : sys.body_names;
      for (std::size_t k = 0; k < names.size(); ++k)
        if (names[k] == sel.name) name_index = static_cast<int>(k);
      if (name_index < 0) throw SceneError(what + ": " + sel.describe() + " does not exist");
    }
    for (std::size_t i = 0; i < n; ++i) {
      bool pick = false;
      switch (sel.kind) {
        case Selection::Kind::all: pick = true; break;
        case Selection::Kind::region: pick = sel.region.contains(sys.position[i]); break;
        case Selection::Kind::phase: pick = sys.phase[i] == name_index; break;
        case Selection::Kind::body: pick = sys.body[i] == name_index; break;
        default: break;
      }
      if (pick) out.push_back(static_cast<int>(i));
    }
  }
  if (out.empty()) throw SceneError(what + ": " + sel.describe() + " selects no particle");
  return out;
}

double pair_dt_limit(const System& sys, bool at_r_min) {
  double limit = INFINITY;
  const std::size_t np = sys.phase_names.size();
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b) {
      const PairLaw& law = sys.law(static_cast<int>(a), static_cast<int>(b));
      const double m = std::min(sys.phase_mass[a], sys.phase_mass[b]);
      const double r = at_r_min && sys.r_min > 0.0 ? sys.r_min : law.equilibrium_spacing();
      limit = std::min(limit, dt_limit(law, m, r));
    }
  return limit;
}

namespace {
// The largest eigenvalue of the symmetric tridiagonal matrix with diagonal a and off-diagonal b, by bisection
// on its Sturm sequence (the count of eigenvalues below x is the count of negative pivots of T - x I).
double largest_tridiagonal_eigenvalue(const std::vector<double>& a, const std::vector<double>& b) {
  double lo = INFINITY, hi = -INFINITY;  // Gershgorin
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double radius = (i > 0 ? std::abs(b[i - 1]) : 0.0) + (i < b.size() ? std::abs(b[i]) : 0.0);
    lo = std::min(lo, a[i] - radius);
    hi = std::max(hi, a[i] + radius);
  }
  const auto below = [&](double x) {
    std::size_t count = 0;
    double pivot = 1.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      pivot = a[i] - x - (i > 0 ? b[i - 1] * b[i - 1] / pivot : 0.0);
      if (pivot == 0.0) pivot = -1e-300;
      if (pivot < 0.0) ++count;
    }
    return count;
  };
  for (int k = 0; k < 200 && hi - lo > 1e-13 * std::max(std::abs(lo), std::abs(hi)); ++k) {
    const double mid = 0.5 * (lo + hi);
    if (below(mid) == a.size())
      hi = mid;
    else
      lo = mid;
  }
  return hi;
}
}  // namespace

namespace {
// lattice_dt_limit in D dimensions. The vectors hold D components, not 3: in 2-D the third is zero in every
// product, so dropping it changes no bit of the result and a third of the memory traffic, which is all this
// costs at millions of particles. The vector passes that follow one another are fused; each sum still runs
// over i in order, so the result is the same to the bit.
template <int D>
double lanczos_dt_limit(const System& sys) {
  using VecD = Eigen::Matrix<double, D, 1>;
  const std::size_t n = sys.size();
  // A spring is its stiffness; its ends are the System's bond, and its direction is made again from the
  // positions in each product, by the same operations, so to the same bits. Keeping the directions would
  // cost D doubles a bond (48 B a particle in 2-D, 144 B in 3-D), the largest part of the setup's peak memory;
  // making them costs about a tenth more time here (docs/performance.md, "Memory at millions of particles").
  const auto direction = [&](std::size_t i, std::size_t j) -> VecD {
    // In 2-D the third component is zero: it adds nothing to the norm, so it is left out.
    const VecD d = (sys.position[j] - sys.position[i]).template head<D>();
    return d / d.norm();
  };
  std::vector<double> stiffness;
  stiffness.reserve(sys.bonds.size());
  for (const auto& b : sys.bonds) {
    const std::size_t i = static_cast<std::size_t>(b[0]), j = static_cast<std::size_t>(b[1]);
    const double r = (sys.position[j] - sys.position[i]).norm();
    stiffness.push_back(std::max(0.0, sys.law(sys.phase[i], sys.phase[j]).stiffness(r)));
  }
  std::vector<double> w_of_phase(sys.phase_mass.size());  // M^-1/2, looked up by phase (not an N-long array)
  for (std::size_t a = 0; a < w_of_phase.size(); ++a) w_of_phase[a] = 1.0 / std::sqrt(sys.phase_mass[a]);
  const auto apply = [&](const std::vector<VecD>& v, std::vector<VecD>& Av) {
    std::fill(Av.begin(), Av.end(), VecD::Zero());
    for (std::size_t b = 0; b < stiffness.size(); ++b) {
      const std::size_t i = static_cast<std::size_t>(sys.bonds[b][0]), j = static_cast<std::size_t>(sys.bonds[b][1]);
      const VecD e = direction(i, j);
      const double wi = w_of_phase[static_cast<std::size_t>(sys.phase[i])];
      const double wj = w_of_phase[static_cast<std::size_t>(sys.phase[j])];
      const double t = stiffness[b] * e.dot(wi * v[i] - wj * v[j]);
      Av[i] += (wi * t) * e;
      Av[j] -= (wj * t) * e;
    }
  };
  std::vector<VecD> q(n, VecD::Zero()), q_prev(n, VecD::Zero()), r(n);
  std::uint64_t seed = 0x9E3779B97F4A7C15ull;  // fixed start: the same limit every time
  for (auto& x : q)
    for (int d = 0; d < D; ++d) {
      seed = seed * 6364136223846793005ull + 1442695040888963407ull;
      x[d] = static_cast<double>(seed >> 11) * 0x1.0p-53 - 0.5;
    }
  double norm0 = 0.0;
  for (std::size_t i = 0; i < n; ++i) norm0 += q[i].dot(q[i]);
  norm0 = std::sqrt(norm0);
  for (auto& x : q) x /= norm0;
  std::vector<double> alpha, beta;  // the tridiagonal T = Q^T A Q
  std::vector<double> largest;      // T's largest eigenvalue after each iteration
  double beta_prev = 0.0;
  for (int it = 0; it < 300; ++it) {
    apply(q, r);
    double a = 0.0;  // q . (A q - beta_prev q_prev)
    for (std::size_t i = 0; i < n; ++i) {
      r[i] -= beta_prev * q_prev[i];
      a += q[i].dot(r[i]);
    }
    double rr = 0.0;  // |r|^2 after removing q
    for (std::size_t i = 0; i < n; ++i) {
      r[i] -= a * q[i];
      rr += r[i].dot(r[i]);
    }
    alpha.push_back(a);
    largest.push_back(largest_tridiagonal_eigenvalue(alpha, beta));
    const double b = std::sqrt(rr);
    const std::size_t m = largest.size();
    if (m >= 20 && largest[m - 1] - largest[m - 11] < 1e-5 * largest[m - 1]) break;
    if (b <= 1e-12 * std::abs(largest.back())) break;  // an invariant subspace: T's spectrum is exact there
    beta.push_back(b);
    std::swap(q_prev, q);
    for (std::size_t i = 0; i < n; ++i) q[i] = r[i] / b;
    beta_prev = b;
  }
  const double lambda = largest.empty() ? 0.0 : largest.back();
  return lambda > 0.0 ? 2.0 / std::sqrt(1.01 * lambda) : INFINITY;
}
}  // namespace

double lattice_dt_limit(const System& sys) {
  // The largest eigenvalue of A = M^-1/2 K M^-1/2 (symmetric, same eigenvalues as M^-1 K) by Lanczos: each
  // bond is a spring along its direction with the law's stiffness -dF/dr at its initial length. The largest
  // Ritz value rises towards lambda_max; it stops once it gains less than 1e-5 in 10 iterations (at most 300),
  // and lambda is raised by 1 % for what it may still lack. Measured: the 3-D block stops after ~110
  // iterations 2e-4 below where 300 would take it (the power iteration used before stopped after 400 at
  // 1.7e-3 below, and took 0.5 s of the run's start). The count hardly grows with N: the rectangular plate
  // takes 138 iterations at 2,673 particles and 147 at 2.7M, so the cost is linear in N.
  if (sys.bonds.empty()) return INFINITY;
  return sys.dim == 2 ? lanczos_dt_limit<2>(sys) : lanczos_dt_limit<3>(sys);
}

double lattice_factor(const System& sys) {
  const double pair = pair_dt_limit(sys, false), lattice = lattice_dt_limit(sys);
  return std::isfinite(lattice) ? std::min(1.0, lattice / pair) : 1.0;
}

double system_dt_limit(const System& sys, bool at_r_min) { return lattice_factor(sys) * pair_dt_limit(sys, at_r_min); }

StepChoice choose_step(const Scene& scene, const System& sys) {
  StepChoice c;
  c.lattice_factor = lattice_factor(sys);
  c.pair_limit = pair_dt_limit(sys);
  c.limit = c.lattice_factor * c.pair_limit;
  c.adaptive = scene.time.adaptive;
  if (scene.time.adaptive)
    // 0.9: headroom, so the slight compression of a body at rest does not already halve every step.
    c.dt = scene.time.dt_max > 0.0 ? scene.time.dt_max
                                   : 0.9 * scene.time.safety * c.lattice_factor * pair_dt_limit(sys, false);
  else
    c.dt = scene.time.auto_dt ? scene.time.safety * c.limit : scene.time.dt;
  return c;
}

}  // namespace pmfrag
