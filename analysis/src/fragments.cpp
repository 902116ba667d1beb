#include "pmfrag/analysis/fragments.hpp"

#include "pmfrag/analysis/union_find.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/model/pair_law.hpp"

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

namespace pmfrag::analysis {

BreakCriterion BreakCriterion::parse(const std::string& text) {
  BreakCriterion c;
  if (text == "D" || text == "cutoff") return c;
  if (text == "rd") {
    c.kind = Kind::damage;
    return c;
  }
  char* end = nullptr;
  const double f = std::strtod(text.c_str(), &end);
  if (text.empty() || *end || !(f > 1.0) || !std::isfinite(f))
    throw std::invalid_argument("--break: expected D, rd or a factor > 1 of r0 (got '" + text + "')");
  c.kind = Kind::factor;
  c.factor = f;
  return c;
}

std::optional<BreakCriterion> BreakCriterion::parse_option(const std::string& text) {
  if (text.empty()) return std::nullopt;
  return parse(text);
}

std::string BreakCriterion::describe() const {
  switch (kind) {
    case Kind::cutoff: return "longer than D";
    case Kind::damage: return "longer than the damage spacing r_d";
    case Kind::factor: {
      char b[64];
      std::snprintf(b, sizeof b, "longer than %g r0", factor);
      return b;
    }
  }
  return "?";
}

BondStates::BondStates(std::vector<std::array<int, 2>> bonds, int dim, double threshold_cm)
    : bonds_(std::move(bonds)), dim_(dim), threshold_(threshold_cm) {
  broken_.assign(bonds_.size(), 0);
  char b[96];
  std::snprintf(b, sizeof b, "longer than %.4g cm at a frame (distance reading)", threshold_cm);
  describe_ = b;
}

BondStates::BondStates(std::size_t bonds, BondRecord record) : record_(std::move(record)) {
  broken_.assign(bonds, 0);
  describe_ = record_->model == "cutoff" ? "beyond D, as the engine recorded (cutoff model: a pair back within D is intact)"
                                         : "broken in the simulation, as the engine recorded";
}

BondStates BondStates::open(const H5mdReader& rd, const std::optional<BreakCriterion>& distance) {
  if (!distance && rd.has_bond_record()) {
    BondStates s(rd.bonds().size(), rd.bond_record());
    s.threshold_ = rd.parameter("cutoff");
    return s;
  }
  const BreakCriterion c = distance.value_or(BreakCriterion{});
  BondStates s(rd.bonds(), rd.dim(), break_length(rd, c));
  s.describe_ = c.describe() + " at a frame (distance reading)";
  return s;
}

bool BondStates::covers(long frame) const {
  return !record_ || (frame >= 0 && static_cast<std::size_t>(frame) < record_->rows_at_frame.size());
}

void BondStates::advance(long frame, const std::vector<double>& x) {
  if (record_) {
    if (!covers(frame)) throw std::logic_error("BondStates: the record does not reach frame " + std::to_string(frame));
    const std::size_t until = static_cast<std::size_t>(record_->rows_at_frame[static_cast<std::size_t>(frame)]);
    for (; applied_ < until; ++applied_) {
      const BondEvent& e = record_->events[applied_];
      std::uint8_t& b = broken_[static_cast<std::size_t>(e.bond)];
      count_ += (e.re_formed ? 0 : 1) - b;  // (the reader checked that each row changes the state)
      b = !e.re_formed;
    }
    return;
  }
  const std::size_t d = static_cast<std::size_t>(dim_);
  const double threshold2 = threshold_ * threshold_;
  for (std::size_t b = 0; b < bonds_.size(); ++b) {
    if (broken_[b]) continue;  // irreversible: a bond that re-closes stays broken
    const std::size_t i = static_cast<std::size_t>(bonds_[b][0]) * d, j = static_cast<std::size_t>(bonds_[b][1]) * d;
    double r2 = 0.0;
    for (std::size_t c = 0; c < d; ++c) r2 += (x[i + c] - x[j + c]) * (x[i + c] - x[j + c]);
    if (r2 > threshold2) broken_[b] = 1, ++count_;
  }
}

FragmentTracker::FragmentTracker(std::size_t particles, std::vector<std::array<int, 2>> bonds, std::vector<double> mass)
    : n_(particles), bonds_(std::move(bonds)), mass_(std::move(mass)) {}

FrameLabels FragmentTracker::label(const std::vector<std::uint8_t>& broken) const {
  UnionFind uf(n_);
  std::vector<int> degree(n_, 0), lost(n_, 0);
  for (std::size_t b = 0; b < bonds_.size(); ++b) {
    const auto i = static_cast<std::size_t>(bonds_[b][0]), j = static_cast<std::size_t>(bonds_[b][1]);
    ++degree[i], ++degree[j];
    if (broken[b])
      ++lost[i], ++lost[j];
    else
      uf.unite(i, j);
  }
  // Number fragments by mass, largest first (ties: lowest particle index), so ids are stable and meaningful.
  std::map<std::size_t, std::pair<double, std::size_t>> roots;  // root -> (mass, first particle)
  for (std::size_t i = 0; i < n_; ++i) {
    auto& r = roots[uf.find(i)];
    if (r.first == 0.0) r.second = i;
    r.first += mass_[i];
  }
  std::vector<std::pair<std::size_t, std::pair<double, std::size_t>>> order(roots.begin(), roots.end());
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
    return a.second.first != b.second.first ? a.second.first > b.second.first : a.second.second < b.second.second;
  });
  std::map<std::size_t, int> id;
  for (std::size_t k = 0; k < order.size(); ++k) id[order[k].first] = static_cast<int>(k);
  FrameLabels l;
  l.fragment_id.resize(n_);
  l.fragment_size.resize(n_);
  l.damage.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    const std::size_t r = uf.find(i);
    l.fragment_id[i] = id[r];
    l.fragment_size[i] = static_cast<int>(uf.size_of(r));
    l.damage[i] = degree[i] ? static_cast<double>(lost[i]) / degree[i] : 0.0;
  }
  return l;
}

namespace {

std::vector<Fragment> describe_fragments(const FrameLabels& l, const TrajectoryFrame& f, const std::vector<double>& mass,
                                         int dim) {
  const std::size_t n = mass.size(), d = static_cast<std::size_t>(dim);
  const int count = l.fragment_id.empty() ? 0 : *std::max_element(l.fragment_id.begin(), l.fragment_id.end()) + 1;
  std::vector<Fragment> out(static_cast<std::size_t>(count));
  const bool moving = !f.velocity.empty();  // frames without velocities (output.fields): NaN, not 0
  for (std::size_t i = 0; i < n; ++i) {
    Fragment& g = out[static_cast<std::size_t>(l.fragment_id[i])];
    Eigen::Vector3d x = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
    for (std::size_t c = 0; c < d; ++c)
      x[static_cast<Eigen::Index>(c)] = f.position[i * d + c],
      v[static_cast<Eigen::Index>(c)] = moving ? f.velocity[i * d + c] : std::numeric_limits<double>::quiet_NaN();
    g.particles += 1;
    g.mass += mass[i];
    g.center += mass[i] * x;
    g.velocity += mass[i] * v;
  }
  for (auto& g : out) g.center /= g.mass, g.velocity /= g.mass;
  std::vector<Eigen::Matrix3d> gyr(out.size(), Eigen::Matrix3d::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(l.fragment_id[i]);
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (std::size_t c = 0; c < d; ++c) x[static_cast<Eigen::Index>(c)] = f.position[i * d + c];
    const Eigen::Vector3d r = x - out[k].center;
    gyr[k] += mass[i] * r * r.transpose();
  }
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k].id = static_cast<long>(k);
    gyr[k] /= out[k].mass;
    out[k].radius_of_gyration = std::sqrt(std::max(0.0, gyr[k].trace()));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(gyr[k]);
    const Eigen::Vector3d ev = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    out[k].principal = Eigen::Vector3d(ev[2], ev[1], ev[0]);
  }
  return out;
}

// The tables with ten significant digits, each whole or absent (write_file_atomically).
template <class F>
void write_atomically(const std::filesystem::path& path, F&& body) {
  write_file_atomically(path, [&](std::ostream& out) {
    out.precision(10);
    body(out);
  });
}

}  // namespace

void add_note(std::string& note, const std::string& more) { note += (note.empty() ? "" : "; ") + more; }

std::string run_title(const H5mdReader& rd, const std::string& fallback) {
  std::string title;
  std::stringstream lines(rd.scene_text());
  for (std::string line; std::getline(lines, line);) {
    const auto start = line.find_first_not_of(" \t");
    if (start == std::string::npos || line.compare(start, 5, "title") != 0) continue;
    const auto q1 = line.find('"'), q2 = line.rfind('"');
    if (q1 != std::string::npos && q2 > q1) title = line.substr(q1 + 1, q2 - q1 - 1);
    break;
  }
  if (title.empty()) title = fallback;
  const std::vector<std::string> overrides = rd.overrides();
  if (!overrides.empty()) {
    title += "\n--set ";
    for (std::size_t k = 0; k < overrides.size(); ++k) title += (k ? ", " : "") + overrides[k];
  }
  return title;
}

std::string trajectory_caveats(const H5mdReader& rd) {
  std::string note;
  if (!rd.damage().empty()) add_note(note, "trajectory " + rd.damage());
  if (const std::string why = rd.incomplete(); !why.empty()) add_note(note, "the run " + why);
  return note;
}

double break_length(const H5mdReader& rd, const BreakCriterion& c) {
  switch (c.kind) {
    case BreakCriterion::Kind::cutoff: return rd.parameter("cutoff");
    case BreakCriterion::Kind::factor: return c.factor * rd.parameter("r0");
    case BreakCriterion::Kind::damage: {
      const auto laws = rd.laws();
      if (laws.size() != 1) throw std::runtime_error("--break rd needs a single-phase trajectory (one damage spacing)");
      return laws.front().damage_spacing();
    }
  }
  return 0.0;
}


std::vector<std::uint8_t> target_particles(const H5mdReader& rd) {
  const auto held = rd.held(), body = rd.body();
  std::map<int, bool> free_body;
  for (std::size_t i = 0; i < held.size(); ++i) free_body[body[i]] = free_body[body[i]] || !held[i];
  std::vector<std::uint8_t> target(held.size(), 0);
  for (std::size_t i = 0; i < held.size(); ++i) target[i] = !free_body[body[i]];
  return target;
}

FragmentReport analyse_fragments(const std::string& trajectory, const std::optional<BreakCriterion>& distance) {
  H5mdReader rd(trajectory);
  FragmentReport rep;
  rep.note = trajectory_caveats(rd);
  rep.partial = !rep.note.empty();
  BondStates states = BondStates::open(rd, distance);
  rep.bond_state = states.source();
  rep.threshold_cm = states.threshold_cm();
  const auto laws = rd.laws();
  if (laws.size() == 1) rep.p = laws.front().p, rep.q = laws.front().q;  // several phases: no single (p,q)
  rep.criterion = states.describe();
  const auto mass = rd.mass();
  // Targets' pieces are left out of the counts, fractions and distribution.
  const std::vector<std::uint8_t> target = target_particles(rd);
  for (std::size_t i = 0; i < mass.size(); ++i)
    if (!target[i]) rep.total_mass += mass[i], ++rep.particles;
    else ++rep.target_particles;
  std::vector<double> ke, pe, engine;
  try {
    ke = rd.observable("kinetic_energy");
    pe = rd.observable("potential_energy");
    engine = rd.observable("pairs_beyond_cutoff");
  } catch (const std::exception&) {
  }
  const auto bonds = rd.bonds();
  FragmentTracker tracker(rd.particles(), bonds, mass);
  std::vector<double> x_initial;
  FrameLabels labels;
  TrajectoryFrame last;
  for (long k = 0; k < rd.frames(); ++k) {
    if (!states.covers(k)) {  // a record cut short: the frames after it have no known bond state
      rep.partial = true;
      add_note(rep.note, states.damage() + "; analysed frames 0.." + std::to_string(k - 1));
      break;
    }
    TrajectoryFrame f;
    try {
      f = rd.frame(k);
    } catch (const std::exception& e) {
      rep.partial = true;
      add_note(rep.note, "frame " + std::to_string(k) + " unreadable (" + e.what() + "); analysed frames 0.." +
                             std::to_string(k - 1));
      break;
    }
    states.advance(k, f.position);
    labels = tracker.label(states.broken());
    TimelineRow row;
    row.step = f.step;
    row.time = f.time;
    row.broken = states.broken_count();
    if (static_cast<std::size_t>(k) < engine.size()) row.broken_engine = std::lround(engine[static_cast<std::size_t>(k)]);
    if (k == 0) x_initial = f.position;
    row.crack = crack_extent(x_initial, rd.dim(), bonds, states.broken());
    std::map<int, double> fm;
    std::map<int, long> fn;
    for (std::size_t i = 0; i < mass.size(); ++i)
      if (!target[i]) fm[labels.fragment_id[i]] += mass[i], ++fn[labels.fragment_id[i]];
    row.fragments = static_cast<long>(fm.size());
    long five_pct = 0;
    for (const auto& [id, m] : fm) {
      row.fragments_2plus += fn[id] >= 2;
      row.fragments_1pct += m >= 0.01 * rep.total_mass;
      five_pct += m >= 0.05 * rep.total_mass;
      row.largest_fraction = std::max(row.largest_fraction, m / rep.total_mass);
    }
    row.mean_mass = rep.total_mass / static_cast<double>(row.fragments);
    if (static_cast<std::size_t>(k) < ke.size()) row.kinetic = ke[static_cast<std::size_t>(k)];
    if (static_cast<std::size_t>(k) < pe.size()) row.potential = pe[static_cast<std::size_t>(k)];
    if (rep.onset_time < 0 && row.broken > 0) rep.onset_time = row.time;
    if (rep.separation_time < 0 && five_pct >= 2) rep.separation_time = row.time;
    rep.timeline.push_back(row);
    last = std::move(f);
    ++rep.frames_read;
  }
  if (rep.frames_read == 0) throw std::runtime_error(trajectory + ": no readable frame");
  rep.final_fragments = describe_fragments(labels, last, mass, rd.dim());
  {  // the targets' pieces left out (a fragment never spans two bodies: bonds join particles of one body)
    std::vector<std::uint8_t> target_piece(rep.final_fragments.size(), 0);
    for (std::size_t i = 0; i < mass.size(); ++i)
      if (target[i]) target_piece[static_cast<std::size_t>(labels.fragment_id[i])] = 1;
    std::erase_if(rep.final_fragments, [&](const Fragment& g) { return target_piece[static_cast<std::size_t>(g.id)]; });
  }
  if (rep.final_fragments.size() > 1) rep.second_largest_fraction = rep.final_fragments[1].mass / rep.total_mass;
  // The power law of the final masses, in particles (one mass unit), the largest fragment left out.
  const auto [lightest, heaviest] = std::minmax_element(mass.begin(), mass.end());
  if (*lightest != *heaviest) {
    rep.distribution_note = "particles of several masses: the discrete fit needs one mass unit";
  } else {
    rep.particle_mass = *lightest;
    std::vector<long> sizes;
    for (std::size_t k = 1; k < rep.final_fragments.size(); ++k) sizes.push_back(rep.final_fragments[k].particles);
    rep.distribution = fit_discrete_power_law(sizes, rep.distribution_note);
  }
  return rep;
}

void write_fragment_report(const FragmentReport& r, const std::string& dir_name) {
  namespace fs = std::filesystem;
  const fs::path dir(dir_name);
  write_atomically(dir / "fragments_timeline.csv", [&](std::ostream& o) {
    o << "time_s,step,broken_bonds,broken_bonds_engine,fragments,fragments_2plus,fragments_1pct_mass,"
         "largest_mass_fraction,mean_fragment_mass_g,kinetic_energy_erg,potential_energy_erg,crack_tip_a_x_cm,"
         "crack_tip_a_y_cm,crack_tip_a_z_cm,crack_tip_b_x_cm,crack_tip_b_y_cm,crack_tip_b_z_cm,crack_extent_cm\n";
    for (const auto& t : r.timeline) {
      o << t.time << "," << t.step << "," << t.broken << ",";
      if (t.broken_engine >= 0) o << t.broken_engine;
      o << "," << t.fragments << "," << t.fragments_2plus << ","
        << t.fragments_1pct << "," << t.largest_fraction << "," << t.mean_mass << "," << t.kinetic << "," << t.potential;
      if (t.crack.present)
        o << "," << t.crack.tip_a.x() << "," << t.crack.tip_a.y() << "," << t.crack.tip_a.z() << "," << t.crack.tip_b.x()
          << "," << t.crack.tip_b.y() << "," << t.crack.tip_b.z() << "," << t.crack.extent_cm;
      else
        o << ",,,,,,,0";  // no crack yet: no tips
      o << "\n";
    }
  });
  write_atomically(dir / "fragments_final.csv", [&](std::ostream& o) {
    o << "id,particles,mass_g,com_x_cm,com_y_cm,com_z_cm,v_x_cm_s,v_y_cm_s,v_z_cm_s,radius_of_gyration_cm,"
         "principal_1_cm,principal_2_cm,principal_3_cm\n";
    for (const auto& g : r.final_fragments)
      o << g.id << "," << g.particles << "," << g.mass << "," << g.center.x() << "," << g.center.y() << ","
        << g.center.z() << "," << g.velocity.x() << "," << g.velocity.y() << "," << g.velocity.z() << ","
        << g.radius_of_gyration << "," << g.principal[0] << "," << g.principal[1] << "," << g.principal[2] << "\n";
  });
  write_atomically(dir / "fragment_sizes.csv", [&](std::ostream& o) {
    // Logarithmic mass bins (factor 2) from the smallest fragment up: the count, n(m) (fragments per gram of
    // bin width: its log-log slope is -tau), and the cumulative fraction of the total mass in fragments no
    // heavier than the bin's upper edge.
    o << "mass_low_g,mass_high_g,fragments,cumulative_mass_fraction,n_per_g\n";
    if (r.final_fragments.empty()) return;
    double lo = r.final_fragments.back().mass;
    for (const auto& g : r.final_fragments) lo = std::min(lo, g.mass);
    lo *= 0.999;
    double cumulative = 0.0;
    for (double a = lo; a <= r.total_mass * 1.0001; a *= 2.0) {
      long count = 0;
      for (const auto& g : r.final_fragments)
        if (g.mass > a && g.mass <= 2 * a) ++count, cumulative += g.mass;
      o << a << "," << 2 * a << "," << count << "," << cumulative / r.total_mass << "," << count / a << "\n";
    }
  });
  write_atomically(dir / "fragment_mass_ccdf.csv", [&](std::ostream& o) {
    // Each distinct final mass, heaviest first: how many fragments weigh at least that much, and that count
    // as a fraction of all fragments (the complementary cumulative distribution, P(M >= m)).
    o << "mass_g,particles,fragments_at_least,fraction_at_least\n";
    const double all = static_cast<double>(r.final_fragments.size());
    for (std::size_t k = 0; k < r.final_fragments.size(); ++k) {
      const auto& g = r.final_fragments[k];
      if (k + 1 < r.final_fragments.size() && r.final_fragments[k + 1].mass == g.mass) continue;  // a tie: its last
      o << g.mass << "," << g.particles << "," << k + 1 << "," << static_cast<double>(k + 1) / all << "\n";
    }
  });
  long singles = 0, multi = 0;
  for (const auto& g : r.final_fragments) (g.particles == 1 ? singles : multi) += 1;
  const TimelineRow& end = r.timeline.back();
  nlohmann::ordered_json distribution = nullptr;
  if (const auto& d = r.distribution)
    distribution = {{"exponent", d->exponent},
                    {"exponent_ci", {d->ci_low, d->ci_high}},
                    {"m_min_g", d->s_min * r.particle_mass},
                    {"s_min_particles", d->s_min},
                    {"fragments_fitted", d->fitted},
                    {"ks_distance", d->ks_distance},
                    {"rule", power_law_rule()}};
  const nlohmann::ordered_json summary = {
      {"p", r.p},
      {"q", r.q},
      {"bond_state", r.bond_state},
      {"break_criterion", r.criterion},
      {"break_length_cm", r.threshold_cm},
      {"frames", r.frames_read},
      {"particles", r.particles},
      {"target_particles", r.target_particles},
      {"partial", r.partial},
      {"note", r.note},
      {"onset_time_s", r.onset_time},
      {"separation_time_s", r.separation_time},
      {"final_time_s", end.time},
      {"broken_bonds", end.broken},
      {"broken_bonds_engine", end.broken_engine >= 0 ? nlohmann::ordered_json(end.broken_engine) : nlohmann::ordered_json()},
      {"fragments", end.fragments},
      {"fragments_2plus", multi},
      {"single_particles", singles},
      {"fragments_1pct_mass", end.fragments_1pct},
      {"largest_mass_fraction", end.largest_fraction},
      {"second_largest_mass_fraction", r.second_largest_fraction},
      {"distribution", distribution},
      {"distribution_note", r.distribution_note}};
  write_atomically(dir / "summary.json", [&](std::ostream& o) {
    o << summary.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
  });
}

}  // namespace pmfrag::analysis
