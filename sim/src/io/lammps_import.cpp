// `pmfrag import`: a LAMMPS run of a `pmfrag lammps` deck read back into a pmfrag run folder.
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/io/lammps.hpp"
#include "pmfrag/run/run.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <unordered_map>

namespace pmfrag {

namespace fs = std::filesystem;

namespace {

// One block of a LAMMPS text dump (`dump custom` or `dump local`): the step and its rows of numbers.
struct DumpBlock {
  long step = 0;
  std::vector<std::vector<double>> rows;
  long first_line = 0;  ///< of the block's rows, for messages
};

// A block cut off by the end of the file: a run killed or still going.
struct DumpCut {
  long step;
};

class DumpReader {
 public:
  explicit DumpReader(fs::path path) : path_(std::move(path)), in_(path_) {
    if (!in_) throw std::runtime_error(path_.string() + ": cannot open");
  }
  const fs::path& path() const { return path_; }

  // The next block; nullopt at a clean end of the file; DumpCut if the file ends inside a block.
  std::optional<DumpBlock> next(std::optional<DumpCut>& cut) {
    std::string line;
    if (!get(line)) return std::nullopt;
    expect(line, "ITEM: TIMESTEP");
    DumpBlock b;
    if (!get(line)) return cut = DumpCut{-1}, std::nullopt;
    b.step = integer(line);
    if (!get(line)) return cut = DumpCut{b.step}, std::nullopt;
    if (line != "ITEM: NUMBER OF ATOMS" && line != "ITEM: NUMBER OF ENTRIES")
      fail("expected \"ITEM: NUMBER OF ATOMS\" or \"ITEM: NUMBER OF ENTRIES\", found \"" + line + "\"");
    if (!get(line)) return cut = DumpCut{b.step}, std::nullopt;
    const long n = integer(line);
    for (int k = 0; k < 4; ++k)  // the box: its header and three lines
      if (!get(line)) return cut = DumpCut{b.step}, std::nullopt;
    if (!get(line)) return cut = DumpCut{b.step}, std::nullopt;
    if (line.rfind("ITEM: ATOMS", 0) != 0 && line.rfind("ITEM: ENTRIES", 0) != 0)
      fail("expected \"ITEM: ATOMS ...\" or \"ITEM: ENTRIES ...\", found \"" + line + "\"");
    std::istringstream header(line.substr(line.find(' ', 6) + 1));
    std::size_t columns = 0;
    for (std::string c; header >> c;) ++columns;
    b.first_line = line_ + 1;
    b.rows.resize(static_cast<std::size_t>(n));
    for (auto& row : b.rows) {
      if (!get(line)) return cut = DumpCut{b.step}, std::nullopt;
      std::istringstream values(line);
      row.reserve(columns);
      for (double v; values >> v;) row.push_back(v);
      // A line cut mid-number at the end of the file reads short: also a cut, when nothing follows.
      if (row.size() != columns) {
        if (in_.peek() == std::char_traits<char>::eof()) return cut = DumpCut{b.step}, std::nullopt;
        fail("expected " + std::to_string(columns) + " numbers, found \"" + line + "\"");
      }
    }
    return b;
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error(path_.string() + ":" + std::to_string(line_) + ": " + why);
  }

 private:
  bool get(std::string& line) {
    if (!std::getline(in_, line)) return false;
    // The last line of a file cut short has no newline: it may be cut mid-way, so it is not read.
    if (in_.eof()) return false;
    ++line_;
    return true;
  }
  void expect(const std::string& line, const char* want) const {
    if (line != want) fail(std::string("expected \"") + want + "\", found \"" + line + "\"");
  }
  long integer(const std::string& line) const {
    std::size_t used = 0;
    long v = 0;
    try {
      v = std::stol(line, &used);
    } catch (const std::exception&) {
      fail("expected a whole number, found \"" + line + "\"");
    }
    if (used != line.size()) fail("expected a whole number, found \"" + line + "\"");
    return v;
  }
  fs::path path_;
  std::ifstream in_;
  long line_ = 0;
};

// log.lammps: the potential energy at each thermo step, and the loop's wall time and process count.
struct LammpsLog {
  std::map<long, double> potential;  ///< erg
  double wall_s = 0.0;
  int procs = 0;
};
LammpsLog read_log(const fs::path& path) {
  LammpsLog log;
  std::ifstream in(path);
  bool table = false;
  for (std::string line; std::getline(in, line);) {
    std::istringstream w(line);
    std::string first;
    w >> first;
    if (first == "Step") {
      table = line.find("PotEng") != std::string::npos;
      continue;
    }
    if (first == "Loop") {  // "Loop time of T on P procs for S steps with N atoms"
      std::string of, time_word, on, procs;
      std::istringstream l(line);
      l >> first >> time_word >> of >> log.wall_s >> on >> log.procs;
      table = false;
      continue;
    }
    if (!table) continue;
    long step = 0;
    double time = 0, ke = 0, pe = 0;
    std::istringstream row(line);
    if (row >> step >> time >> ke >> pe) log.potential[step] = pe;
    else table = false;
  }
  return log;
}

std::uint64_t pair_key(long a, long b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint64_t>(b);
}

}  // namespace

LammpsImport import_lammps_run(const fs::path& deck, const fs::path& out, bool force) {
  if (!fs::exists(deck / "in.lammps") || !fs::exists(deck / "scene.toml"))
    throw std::runtime_error(deck.string() + ": not a LAMMPS deck of pmfrag's (no in.lammps and scene.toml; write one "
                             "with `pmfrag lammps SCENE --out DIR`)");
  const Scene scene = read_folder_scene(deck);
  const System sys = build_system(scene);
  check_lammps_can_run(scene, sys);
  const bool bonded = scene.pair.value_or(PairSpec{}).model == PairModel::bonded;
  const StepChoice choice = choose_step(scene, sys);
  const double dt = choice.dt;
  LammpsImport res;
  res.steps = std::max(1L, std::lround(scene.time.end / dt));
  const long every = std::max(1L, std::lround(scene.output.every / dt));
  const fs::path frames_path = deck / "frames.dump", bonds_path = deck / "bonds.dump";
  if (!fs::exists(frames_path))
    throw std::runtime_error(frames_path.string() + ": not found; run the deck first (cd " + deck.string() +
                             " && mpirun -np N lmp -in in.lammps)");
  if (bonded && !fs::exists(bonds_path))
    throw std::runtime_error(bonds_path.string() + ": not found, and the bonded reading needs it (the deck's in.lammps writes it)");
  const LammpsLog log = read_log(deck / "log.lammps");
  res.lammps_wall_s = log.wall_s, res.lammps_procs = log.procs;

  const FolderLock lock(out);
  start_run_folder(out, scene, force);
  const std::size_t n = sys.size(), dim = static_cast<std::size_t>(sys.dim);
  std::unordered_map<std::uint64_t, long> bond_of;
  for (std::size_t b = 0; b < sys.bonds.size(); ++b) bond_of[pair_key(sys.bonds[b][0], sys.bonds[b][1])] = static_cast<long>(b);
  std::vector<std::uint8_t> broken(sys.bonds.size(), 0);
  long broken_now = 0;

  const RunParameters rp{dt, choice.limit, scene.time.end, every, false};
  write_file_atomically_by_name(out / "trajectory.h5", [&](const fs::path& tmp) {
    H5mdWriter writer(tmp.string(), sys, scene, rp);
    DumpReader frames(frames_path);
    std::optional<DumpReader> bonds;
    if (bonded) bonds.emplace(bonds_path);
    std::vector<double> position(n * dim), velocity(n * dim);
    std::optional<DumpCut> cut;
    long expected_step = 0;
    for (;;) {
      const std::optional<DumpBlock> f = frames.next(cut);
      if (!f) break;
      if (f->rows.size() != n)
        frames.fail("a frame of " + std::to_string(f->rows.size()) + " atoms; the deck's scene has " + std::to_string(n));
      if (f->step != expected_step)
        frames.fail("a frame at step " + std::to_string(f->step) + ", expected step " + std::to_string(expected_step) +
                    " (a frame every " + std::to_string(every) + " steps)");
      std::optional<DumpBlock> bond_block;
      if (bonds) {
        std::optional<DumpCut> bond_cut;
        bond_block = bonds->next(bond_cut);
        if (!bond_block) {  // the bond record ends before the frames: the frames after it are not taken
          cut = DumpCut{f->step};
          res.note = bonds_path.filename().string() + " ends before the frame at step " + std::to_string(f->step);
          break;
        }
        if (bond_block->step != f->step) bonds->fail("bonds at step " + std::to_string(bond_block->step) + ", frames at " + std::to_string(f->step));
      }
      for (std::size_t i = 0; i < n; ++i) {
        const auto& row = f->rows[i];
        if (row.size() < 7 || std::lround(row[0]) != static_cast<long>(i) + 1)
          throw std::runtime_error(frames_path.string() + ":" + std::to_string(f->first_line + static_cast<long>(i)) +
                                   ": expected atom " + std::to_string(i + 1) + " with id x y z vx vy vz (dump_modify sort id)");
        for (std::size_t a = 0; a < dim; ++a) position[i * dim + a] = row[1 + a], velocity[i * dim + a] = row[4 + a];
      }
      const double time = static_cast<double>(f->step) * dt;
      std::vector<BondEvent> events;
      if (bond_block) {  // bonded: a bond missing from this frame's list broke since the previous frame
        std::vector<std::uint8_t> intact(sys.bonds.size(), 0);
        for (const auto& row : bond_block->rows) {
          const auto it = bond_of.find(pair_key(std::lround(row[0]) - 1, std::lround(row[1]) - 1));
          if (it == bond_of.end()) bonds->fail("a bond between atoms " + std::to_string(std::lround(row[0])) + " and " +
                                               std::to_string(std::lround(row[1])) + ", which the scene does not bond");
          intact[static_cast<std::size_t>(it->second)] = 1;
        }
        for (std::size_t b = 0; b < broken.size(); ++b)
          if (!intact[b] && !broken[b]) broken[b] = 1, ++broken_now, events.push_back({f->step, time, static_cast<long>(b), false});
      } else {  // cutoff: a pair of the lattice is broken while it is farther apart than D
        for (std::size_t b = 0; b < broken.size(); ++b) {
          const std::size_t i = static_cast<std::size_t>(sys.bonds[b][0]), j = static_cast<std::size_t>(sys.bonds[b][1]);
          double r2 = 0.0;
          for (std::size_t a = 0; a < dim; ++a) r2 += std::pow(position[i * dim + a] - position[j * dim + a], 2);
          const std::uint8_t beyond = r2 > sys.cutoff * sys.cutoff;
          if (beyond == broken[b]) continue;
          broken[b] = beyond;
          broken_now += beyond ? 1 : -1;
          events.push_back({f->step, time, static_cast<long>(b), !beyond});
          ++(beyond ? res.bonds_broken : res.bonds_re_formed);
        }
      }
      if (bonded) res.bonds_broken = broken_now;
      if (!events.empty() && res.first_break_time < 0) res.first_break_time = time;
      writer.append_bond_events(events);
      Observables obs;
      for (std::size_t i = 0; i < n; ++i) {
        double v2 = 0.0;
        for (std::size_t a = 0; a < dim; ++a) v2 += velocity[i * dim + a] * velocity[i * dim + a];
        obs.kinetic += 0.5 * sys.phase_mass[static_cast<std::size_t>(sys.phase[i])] * v2;
      }
      const auto pe = log.potential.find(f->step);
      obs.potential = pe != log.potential.end() ? pe->second : std::numeric_limits<double>::quiet_NaN();
      // Not in LAMMPS' output: the work of the kinematic rows and the energy of the broken bonds.
      obs.boundary_work = obs.bond_break_energy = std::numeric_limits<double>::quiet_NaN();
      obs.pairs_beyond_cutoff = broken_now;
      writer.write_frame(f->step, time, position, velocity, obs);
      res.frames += 1;
      res.last_step = f->step;
      expected_step = f->step + every;
    }
    if (res.frames == 0) throw std::runtime_error(frames_path.string() + ": no whole frame");
    if (cut && res.note.empty())
      res.note = frames_path.filename().string() + " ends inside the frame at step " + std::to_string(cut->step);
    if (res.last_step + every <= res.steps) {  // LAMMPS dumps every `every` steps, from step 0
      res.partial = true;
      const std::string why = "stopped at step " + std::to_string(res.last_step) + " of " + std::to_string(res.steps) +
                              " in LAMMPS" + (res.note.empty() ? "" : " (" + res.note + ")");
      res.note = why;
      writer.mark_incomplete(why);
    }
    writer.close();
    return true;
  });

  const nlohmann::ordered_json record = {
      {"completed", !res.partial},
      {"interrupted", false},
      {"message", res.partial ? res.note : "imported from the LAMMPS run in " + deck.string()},
      {"engine", "LAMMPS"},
      {"lammps_folder", fs::absolute(deck).string()},
      {"particles", n},
      {"steps", res.last_step},
      {"frames", res.frames},
      {"dt_s", dt},
      {"dt_limit_s", choice.limit},
      {"wall_s", res.lammps_wall_s},
      {"lammps_procs", res.lammps_procs},
      {"pair_model", bonded ? "bonded" : "cutoff"},
      {"first_break_time_s", res.first_break_time},
      {"bond_events_dated_by", "frame"},
      {"bond_events", {{"broken", res.bonds_broken}, {"re_formed", res.bonds_re_formed}, {"beyond_cutoff_at_end", broken_now}}}};
  write_file_atomically(out / "run.json", [&](std::ostream& js) { js << record.dump(2) << "\n"; });
  return res;
}

}  // namespace pmfrag
