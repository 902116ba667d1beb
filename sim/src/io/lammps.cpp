#include "pmfrag/io/lammps.hpp"

#include "pmfrag/io/atomic_file.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

namespace pmfrag {

namespace fs = std::filesystem;

namespace {

// Rows of the tabulated bond, from 0.5 r0 to D: linear interpolation between them put the plate within
// 1.9e-8 cm of pmfrag's analytic law over 100,000 steps (bench/compare-lammps.sh).
constexpr int bond_table_rows = 20000;

// The atom type of each particle: 1 free, 2 + k for the k-th [[kinematic]] selection (the last one wins, as
// the engine's kinematic effects are applied in order).
std::vector<int> atom_types(const Scene& scene, const System& sys) {
  std::vector<int> type(sys.size(), 1);
  for (std::size_t k = 0; k < scene.kinematic.size(); ++k)
    for (int i : select_particles(sys, scene.kinematic[k].select, "kinematic"))
      type[static_cast<std::size_t>(i)] = static_cast<int>(k) + 2;
  return type;
}

// Mie's law, E = C eps [(s/r)^gR - (s/r)^gA] with C = gR/(gR-gA) (gR/gA)^(gA/(gR-gA)), is -G/r^p + H/r^q in
// force for gR = q - 1, gA = p - 1 and these eps [erg] and sigma [cm].
struct Mie {
  double eps, sigma;
  int gR, gA;
};
Mie mie_of(const PairLaw& law) {
  Mie m{0, 0, law.q - 1, law.p - 1};
  const double gR = m.gR, gA = m.gA;
  const double C = gR / (gR - gA) * std::pow(gR / gA, gA / (gR - gA));
  m.sigma = std::pow(law.H * gA / (law.G * gR), 1.0 / (law.q - law.p));
  m.eps = law.G / (gA * C * std::pow(m.sigma, gA));
  return m;
}

// The shortest text that reads back as the same double (in.lammps stays readable and exact).
std::string num(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

}  // namespace

void check_lammps_can_run(const Scene& scene, const System& sys) {
  const PairSpec pair = scene.pair.value_or(PairSpec{});
  const auto refuse = [&](const std::string& what) {
    throw LammpsUnsupported(scene.file + ": " + what + " cannot be written for LAMMPS (pmfrag lammps runs one phase, a fixed step, "
                            "kinematic selections and impactors, both readings of the pair law)");
  };
  if (sys.phase_names.size() != 1) refuse("a scene of " + std::to_string(sys.phase_names.size()) + " phases");
  if (scene.time.adaptive) refuse("time.dt = \"adaptive\"");
  if (scene.gravity) refuse("[gravity]");
  if (scene.damping) refuse("[damping]");
  if (scene.greenspan_alpha) refuse("[greenspan_alpha] (Eq. 10's pseudo-dynamic scaling)");
  if (pair.r_min_r0 > 0.0) refuse("pair.r_min (the force held constant inside r_min)");
  if (pair.single_precision) refuse("pair.precision = \"float\"");
  if (sys.laws.front().p < 2) refuse("p = 1 (LAMMPS' mie/cut needs an attraction exponent p >= 2)");
}

void write_lammps_data(const fs::path& path, const Scene& scene, const System& sys) {
  const std::vector<int> type = atom_types(scene, sys);
  const bool bonded = scene.pair.value_or(PairSpec{}).model == PairModel::bonded;
  // The cutoff reading has no bonds in LAMMPS: its lattice pairs may drift apart without limit, and LAMMPS
  // stops ("bond atoms missing") when a bond's ends leave one process's reach.
  const std::size_t bonds = bonded ? sys.bonds.size() : 0;
  Vec3 lo = sys.position.front(), hi = lo;
  for (const auto& x : sys.position) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  const double pad = 5.0 * sys.r0;
  write_file_atomically(path, [&](std::ostream& f) {
    f.precision(17);
    f << "# pmfrag scene " << scene.file << " (" << sys.size() << " particles, " << bonds << " bonds), CGS units\n\n";
    f << sys.size() << " atoms\n" << bonds << " bonds\n" << scene.kinematic.size() + 1 << " atom types\n1 bond types\n\n";
    f << lo.x() - pad << " " << hi.x() + pad << " xlo xhi\n" << lo.y() - pad << " " << hi.y() + pad << " ylo yhi\n";
    if (sys.dim == 3)
      f << lo.z() - pad << " " << hi.z() + pad << " zlo zhi\n";
    else
      f << "-0.5 0.5 zlo zhi\n";
    f << "\nMasses\n\n";
    for (std::size_t t = 1; t <= scene.kinematic.size() + 1; ++t) f << t << " " << sys.phase_mass.front() << "\n";
    f << "\nAtoms # bond\n\n";
    for (std::size_t i = 0; i < sys.size(); ++i)
      f << i + 1 << " 1 " << type[i] << " " << sys.position[i].x() << " " << sys.position[i].y() << " "
        << sys.position[i].z() << "\n";
    f << "\nVelocities\n\n";
    for (std::size_t i = 0; i < sys.size(); ++i)
      f << i + 1 << " " << sys.velocity[i].x() << " " << sys.velocity[i].y() << " " << sys.velocity[i].z() << "\n";
    if (bonds > 0) {
      f << "\nBonds\n\n";
      for (std::size_t b = 0; b < bonds; ++b) f << b + 1 << " 1 " << sys.bonds[b][0] + 1 << " " << sys.bonds[b][1] + 1 << "\n";
    }
  });
}

LammpsDeck write_lammps_deck(const Scene& scene, const System& sys, const fs::path& dir) {
  check_lammps_can_run(scene, sys);
  const PairSpec pair = scene.pair.value_or(PairSpec{});
  const bool bonded = pair.model == PairModel::bonded;
  const PairLaw& law = sys.laws.front();
  LammpsDeck deck;
  deck.dt = choose_step(scene, sys).dt;
  deck.steps = std::max(1L, std::lround(scene.time.end / deck.dt));
  deck.frame_every = std::max(1L, std::lround(scene.output.every / deck.dt));

  make_folder(dir);
  deck.files = {"in.lammps", "data.lammps"};
  write_lammps_data(dir / "data.lammps", scene, sys);
  if (bonded) {
    deck.files.push_back("bond.table");
    write_file_atomically(dir / "bond.table", [&](std::ostream& f) {
      f.precision(17);
      f << "# the (" << law.p << "," << law.q << ") law of " << scene.file << ": r [cm], energy [erg], force [dyne]\n\nPQ\nN "
        << bond_table_rows << "\n\n";
      const double lo = 0.5 * sys.r0, hi = sys.cutoff;
      for (int k = 0; k < bond_table_rows; ++k) {
        const double r = lo + (hi - lo) * k / (bond_table_rows - 1);
        f << k + 1 << " " << r << " " << law.potential(r) << " " << law.force(r) << "\n";
      }
    });
  }
  // The scene as read and its overrides, as in a run folder: `pmfrag import` rebuilds the particles from them.
  deck.files.insert(deck.files.end(), {"scene.toml", "overrides.txt"});
  write_file_atomically(dir / "scene.toml", [&](std::ostream& s) { s << scene.source; });
  write_file_atomically(dir / "overrides.txt", [&](std::ostream& ov) {
    ov << "# source: " << scene.file << "\n";
    for (const auto& o : scene.overrides) ov << o << "\n";
  });

  const Mie mie = mie_of(law);
  const double skin = 0.3 * sys.r0;
  std::ostringstream in;
  in << "# " << scene.file << (scene.title.empty() ? "" : ": " + scene.title) << "\n"
     << "# Written by `pmfrag lammps`. Run: cd THIS_FOLDER && mpirun -np N lmp -in in.lammps\n"
     << "# Then: pmfrag import THIS_FOLDER --out RUN (fragments, export, render and the studies read RUN).\n"
     << "# (p,q) = (" << law.p << "," << law.q << "), G = " << num(law.G) << " dyne cm^p, H = " << num(law.H) << " dyne cm^q, r0 = "
     << num(sys.r0) << " cm, D = " << num(sys.cutoff) << " cm, " << (bonded ? "bonded" : "cutoff") << " reading\n\n"
     << "units cgs\ndimension " << sys.dim << "\nboundary s s " << (sys.dim == 2 ? "p" : "s") << "\natom_style bond\n"
     << "read_data data.lammps\n\n";
  if (bonded) {
    in << "# The original bonds carry the law and break for good past D; unbonded pairs (broken bonds among them)\n"
       << "# repel within r0 through the same law, as pmfrag's contacts.\n"
       << "bond_style table linear " << bond_table_rows << "\nbond_coeff 1 bond.table PQ\n";
    if (pair.contact)
      in << "pair_style mie/cut " << num(sys.r0) << "\npair_coeff * * " << num(mie.eps) << " " << num(mie.sigma) << " " << mie.gR << " " << mie.gA << "\n";
    else
      in << "pair_style zero " << num(sys.r0) << "\npair_coeff * *\n";
    in << "special_bonds lj 0 1 1\n"
       << "# fix bond/break rewrites the special lists of a broken bond's 1-3 and 1-4 neighbours, up to three bonds\n"
       << "# (3 D) away: every process keeps ghosts that far.\n"
       << "comm_modify cutoff " << num(3.0 * sys.cutoff + skin) << "\n"
       << "fix break all bond/break 1 1 " << num(sys.cutoff) << "\n";
  } else {
    in << "# Every pair within D interacts through the law (mie/cut with these eps, sigma, exponents).\n"
       << "pair_style mie/cut " << num(sys.cutoff) << "\npair_coeff * * " << num(mie.eps) << " " << num(mie.sigma) << " " << mie.gR << " "
       << mie.gA << "\n";
  }
  in << "neighbor " << num(skin) << " bin\nneigh_modify every 1 delay 0 check yes\n\n";
  for (std::size_t k = 0; k < scene.kinematic.size(); ++k) {
    const KinematicSpec& kin = scene.kinematic[k];
    const std::string g = "kinematic_" + std::to_string(k + 1);
    in << "# [[kinematic]] " << k + 1 << ": " << kin.select.describe() << ", moved at constant velocity [cm/s]\n"
       << "group " << g << " type " << k + 2 << "\n"
       << "velocity " << g << " set " << num(kin.velocity.x()) << " " << num(kin.velocity.y()) << " " << num(kin.velocity.z()) << "\n"
       << "fix hold_" << k + 1 << " " << g << " setforce 0 0 0\n";
  }
  in << "fix move all nve\n";
  if (sys.dim == 2) in << "fix flat all enforce2d\n";
  in << "timestep " << num(deck.dt) << "\n\n"
     << "# A frame every " << deck.frame_every << " steps (output.every = " << num(scene.output.every) << " s).\n"
     << "dump frames all custom " << deck.frame_every << " frames.dump id x y z vx vy vz\n"
     << "dump_modify frames sort id format float %.17g\n";
  if (bonded)
    in << "compute intact all property/local batom1 batom2\n"
       << "dump bonds all local " << deck.frame_every << " bonds.dump c_intact[1] c_intact[2]\n";
  in << "thermo_style custom step time ke pe\nthermo_modify norm no format float %.17g\nthermo " << deck.frame_every << "\n"
     << "run " << deck.steps << "\n";
  write_file_atomically(dir / "in.lammps", [&](std::ostream& f) { f << in.str(); });
  return deck;
}

}  // namespace pmfrag
