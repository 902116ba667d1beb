// `pmfrag study accuracy SCENE --out DIR`: the same scene at several time steps and lattice spacings; for
// each run the wall time and what it bought (energy balance, positions before fracture, onset time, fragment
// count) against the finest run of its knob. Wiring only: runs are sim/, fragments are analysis/, the chart
// is render/.
#include "cmd_study.hpp"

#include "parse.hpp"
#include "run_files.hpp"
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/render/charts.hpp"
#include "pmfrag/run/run.hpp"
#include "pmfrag/body/system.hpp"


#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>

namespace pmfrag::app {

namespace {

namespace fs = std::filesystem;

struct StudyCli {
  std::string scene, out, dts, r0s, png, knobs = "dt,r0";
  bool reuse = false;
  std::vector<std::string> set;
  int threads = 0;
};

struct Row {
  std::string knob;  // "dt" or "r0"
  double value = 0, dt = 0, r0 = 0;
  std::size_t particles = 0;
  long steps = 0;
  double wall = 0, pss = 0, energy_error = NAN, position_error = NAN, onset = NAN, onset_error = NAN,
         separation = NAN;
  long fragments = 0;
  std::string status = "completed";  // or why the run stopped (the guard): kept in the CSV, left off the chart
  fs::path dir;
};

std::vector<double> number_list(const std::string& option, const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
    }
    if (used != item.size() || !(v > 0)) throw UsageError(option + ": '" + item + "' is not a positive number");
    out.push_back(v);
  }
  if (out.empty()) throw UsageError(option + ": give at least one value");
  return out;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// Positions at time t, from the frame nearest t moved along its velocity (frames of runs with different dt
// do not fall on the same times).
std::vector<double> positions_at(const H5mdReader& rd, double t) {
  const auto times = rd.times();
  long best = 0;
  for (long k = 1; k < static_cast<long>(times.size()); ++k)
    if (std::fabs(times[static_cast<std::size_t>(k)] - t) < std::fabs(times[static_cast<std::size_t>(best)] - t)) best = k;
  const TrajectoryFrame f = rd.frame(best);
  std::vector<double> x = f.position;
  if (t == f.time) return x;
  if (f.velocity.empty())
    throw std::runtime_error(rd.path() + ": no velocities to move frame " + std::to_string(best) + " to t = " +
                             std::to_string(t) + " s (output.fields left them out)");
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += f.velocity[i] * (t - f.time);
  return x;
}

Row run_one(const StudyCli& o, const std::string& knob, double value, const std::vector<std::string>& extra) {
  Row row;
  row.knob = knob;
  row.value = value;
  row.dir = fs::path(o.out) / (knob + "_" + num(value));
  std::vector<std::string> set = o.set;
  set.insert(set.end(), extra.begin(), extra.end());
  const Scene sc = read_scene(o.scene, set);
  RunOptions ro;
  ro.out_dir = row.dir.string();
  ro.force = true;
  ro.threads = thread_options_from_environment(o.threads);
  RunResult r;
  const std::string recorded = slurp(row.dir / "overrides.txt");
  std::string wanted = "# source: " + sc.file + "\n";
  for (const auto& s : sc.overrides) wanted += s + "\n";
  if (o.reuse && fs::exists(row.dir / "run.json") && recorded == wanted) {  // the same scene and overrides ran here before
    r = read_run_record((row.dir / "run.json").string());
  } else {
    r = run_scene(sc, ro);
  }
  if (!r.completed) row.status = "stopped: " + r.message;
  const System sys = build_system(sc);
  row.dt = r.dt, row.r0 = sys.r0, row.particles = r.particles, row.steps = r.steps, row.wall = r.wall_s;
  row.pss = r.particle_steps_per_s();
  row.onset = r.first_break_time >= 0 ? r.first_break_time : NAN;
  H5mdReader rd((row.dir / "trajectory.h5").string());
  const auto bal = rd.observable("energy_balance"), work = rd.observable("boundary_work");
  double worst = 0;
  for (double b : bal) worst = std::max(worst, std::fabs(b - bal.front()));
  row.energy_error = work.back() > 0 ? worst / work.back() : NAN;
  const auto rep = analysis::analyse_fragments((row.dir / "trajectory.h5").string(), {});
  row.fragments = rep.timeline.back().fragments_2plus;
  row.separation = rep.separation_time >= 0 ? rep.separation_time : NAN;
  std::printf("  %s = %-9s dt %.3g s, r0 %.3g cm, %zu particles, %ld steps, %.2f s wall, onset %.6g s, %ld fragments%s\n",
              knob.c_str(), num(value).c_str(), row.dt, row.r0, row.particles, row.steps, row.wall, row.onset,
              row.fragments, row.status == "completed" ? "" : (" - " + row.status).c_str());
  std::fflush(stdout);
  return row;
}

void study_accuracy(const StudyCli& o) {
  const Scene sc = read_scene(o.scene, o.set);
  if (!sc.output.velocity)  // positions between frames are moved there along the velocities
    throw UsageError(o.scene + ": the accuracy study needs velocities in the frames; drop output.fields = [\"position\"]");
  const System sys = build_system(sc);
  const double limit = choose_step(sc, sys).limit;
  make_folder(o.out);
  std::vector<Row> rows;

  const bool want_dt = o.knobs.find("dt") != std::string::npos, want_r0 = o.knobs.find("r0") != std::string::npos,
             want_float = o.knobs.find("precision") != std::string::npos;
  if (want_float && !want_dt) throw UsageError("--knobs: precision is measured against the dt runs; add dt");
  // Time step: from 1e-8 s to near the limit; the finest run is the reference.
  std::vector<double> dts = o.dts.empty() ? std::vector<double>{1e-8, 2e-8, 5e-8, 1e-7, 2e-7, 0.9 * limit}
                                          : number_list("--dt", o.dts);
  std::sort(dts.begin(), dts.end());
  dts.erase(std::remove_if(dts.begin(), dts.end(), [&](double d) { return d > limit; }), dts.end());
  if (dts.empty()) throw UsageError("--dt: every value is above the stability limit " + num(limit) + " s");
  std::vector<Row> by_dt;
  if (want_dt) std::printf("time step (stability limit %.4g s):\n", limit);
  if (want_dt)
    for (double dt : dts) by_dt.push_back(run_one(o, "dt", dt, {"time.dt=" + num(dt)}));
  // Precision: the same time steps with the bond sweeps in single precision, against the same (double)
  // reference; at the finest dt the difference is the rounding alone.
  std::vector<Row> by_float;
  if (want_float) {
    std::printf("single precision bond sweeps (pair.precision = \"float\"):\n");
    for (double dt : dts)
      by_float.push_back(run_one(o, "float", dt, {"time.dt=" + num(dt), "pair.precision=\"float\""}));
  }
  if (!by_dt.empty() && std::isfinite(by_dt.front().onset)) {
    const Row& ref = by_dt.front();
    // The reference's frame nearest 0.8 x its onset: runs whose dt divides the output interval have a frame
    // at exactly that time; others are moved there along their velocities.
    H5mdReader rr((ref.dir / "trajectory.h5").string());
    double t_pre = 0.0;
    for (double t : rr.times())
      if (std::fabs(t - 0.8 * ref.onset) < std::fabs(t_pre - 0.8 * ref.onset)) t_pre = t;
    const auto x_ref = positions_at(rr, t_pre), x0 = rr.frame(0).position;
    double disp2 = 0;
    for (std::size_t i = 0; i < x_ref.size(); ++i) disp2 += (x_ref[i] - x0[i]) * (x_ref[i] - x0[i]);
    std::vector<Row*> measured;
    for (auto& row : by_dt) measured.push_back(&row);
    for (auto& row : by_float) measured.push_back(&row);
    for (Row* rp : measured) {
      Row& row = *rp;
      H5mdReader rd((row.dir / "trajectory.h5").string());
      const auto x = positions_at(rd, t_pre);
      double e2 = 0;
      for (std::size_t i = 0; i < x.size(); ++i) e2 += (x[i] - x_ref[i]) * (x[i] - x_ref[i]);
      row.position_error = std::sqrt(e2 / disp2);
      // The first break is resolved to one step: an error below the run's dt is reported as dt.
      row.onset_error = &row == &by_dt.front() ? 0.0 : std::max(std::fabs(row.onset - ref.onset), row.dt) / ref.onset;
    }
  }
  rows.insert(rows.end(), by_dt.begin(), by_dt.end());
  rows.insert(rows.end(), by_float.begin(), by_float.end());

  // Lattice spacing: the same body at several r0, each at a quarter of its own limit; finest r0 = reference.
  const bool can_scale = !sc.bodies.empty() && sc.bodies.front().lattice != LatticeKind::greenspan_plate;
  std::vector<double> r0s = o.r0s.empty() ? std::vector<double>{0.4, 0.2, 0.1} : number_list("--r0", o.r0s);
  std::sort(r0s.begin(), r0s.end());
  if (!want_r0) {
  } else if (!can_scale) {
    std::printf("lattice spacing: skipped (the Greenspan mesh has a fixed r0; use a rect-lattice scene such as "
                "cases/slit_plate_rect_7_14.toml)\n");
  } else {
    std::printf("lattice spacing:\n");
    std::vector<Row> by_r0;
    for (double r0 : r0s) {
      std::vector<std::string> extra;
      for (std::size_t b = 0; b < sc.bodies.size(); ++b) extra.push_back("body." + std::to_string(b) + ".r0=" + num(r0));
      const Scene scaled = read_scene(o.scene, [&] {
        auto s = o.set;
        s.insert(s.end(), extra.begin(), extra.end());
        return s;
      }());
      const double lim = choose_step(scaled, build_system(scaled)).limit;
      extra.push_back("time.dt=" + num(0.25 * lim));
      by_r0.push_back(run_one(o, "r0", r0, extra));
    }
    const Row& fine = by_r0.front();
    for (auto& row : by_r0)
      if (std::isfinite(fine.onset))
        row.onset_error = &row == &by_r0.front() ? 0.0 : std::max(std::fabs(row.onset - fine.onset), row.dt) / fine.onset;
    rows.insert(rows.end(), by_r0.begin(), by_r0.end());
  }

  const fs::path csv = fs::path(o.out) / "accuracy.csv";
  write_file_atomically(csv, [&](std::ostream& f) {
    f << "knob,value,dt_s,r0_cm,particles,steps,wall_s,particle_steps_per_s,energy_error_of_work,"
         "position_error_rel,onset_s,onset_rel_error,separation_s,fragments,status\n";
    for (const auto& r : rows)
      f << r.knob << "," << num(r.value) << "," << num(r.dt) << "," << num(r.r0) << "," << r.particles << "," << r.steps
        << "," << num(r.wall) << "," << num(r.pss) << "," << num(r.energy_error) << "," << num(r.position_error) << ","
        << num(r.onset) << "," << num(r.onset_error) << "," << num(r.separation) << "," << r.fragments << ",\""
        << r.status << "\"\n";
  });

  render::ChartSpec chart;
  chart.title = "What accuracy costs: error against wall time (" + fs::path(o.scene).filename().string() + ")";
  chart.x_label = "wall time [s] (2 cores)";
  chart.y_label = "relative error against the finest run";
  chart.log_x = chart.log_y = true;
  render::Series dt_pos{"dt: positions at 0.8 x onset", {}, {}}, dt_onset{"dt: onset time", {}, {}},
      r0_onset{"r0: onset time", {}, {}}, float_pos{"float (dt as above): positions at 0.8 x onset", {}, {}};
  for (const auto& r : rows) {
    if (r.status != "completed") continue;
    if (r.knob == "float") {
      float_pos.x.push_back(r.wall), float_pos.y.push_back(r.position_error);
    } else if (r.knob == "dt") {
      dt_pos.x.push_back(r.wall), dt_pos.y.push_back(r.position_error);
      dt_onset.x.push_back(r.wall), dt_onset.y.push_back(r.onset_error);
    } else {
      r0_onset.x.push_back(r.wall), r0_onset.y.push_back(r.onset_error);
    }
  }
  chart.series = {dt_pos, dt_onset};
  if (!r0_onset.x.empty()) chart.series.push_back(r0_onset);
  if (!float_pos.x.empty()) chart.series.push_back(float_pos);
  const std::string png = o.png.empty() ? (fs::path(o.out) / "accuracy.png").string() : o.png;
  render::HeadlessWindow window(1000, 700);
  render::render_chart_png(window, chart, 1000, 700, png);
  std::printf("wrote %s and %s\n", csv.c_str(), png.c_str());
}

// One CSV line's cells; a quoted cell may hold commas (sweep.csv quotes the varied values and the status).
std::vector<std::string> csv_cells(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      cells.emplace_back();
    else
      cells.back() += c;
  }
  return cells;
}

double cell_number(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end != text.c_str() ? v : NAN;
}

// `pmfrag study sweep-figures SWEEP_DIR`: charts of sweep.csv. Over (p,q) alone: onset and separation time and
// fragment counts against the modulus E of each (p,q) (E orders the pairs from soft to stiff, as in Fig. 3).
// Over impact speeds (a varied impactor velocity): per (p,q), the pieces and the largest piece against the
// speed, tau against the impact energy per unit mass, and n(m) of the fastest case of each law with its fit.
void sweep_figures(const std::string& dir, const std::string& prefix) {
  const fs::path csv = fs::path(dir) / "sweep.csv";
  std::ifstream in(csv);
  if (!in) throw UsageError(csv.string() + ": not found (run `pmfrag sweep` first)");
  std::string header;
  std::getline(in, header);
  const std::vector<std::string> names = csv_cells(header);
  auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw std::runtime_error(csv.string() + ": no column '" + name + "'");
    return static_cast<std::size_t>(it - names.begin());
  };
  const std::size_t cSt = column("status");
  std::vector<std::vector<std::string>> rows;
  long skipped = 0;
  for (std::string line; std::getline(in, line);) {
    auto cells = csv_cells(line);
    if (cells.size() != names.size() || cells[cSt].find("completed") == std::string::npos) {
      ++skipped;
      continue;
    }
    rows.push_back(std::move(cells));
  }
  const auto num = [&](const std::vector<std::string>& r, const std::string& name) { return cell_number(r[column(name)]); };
  render::HeadlessWindow window(1000, 650);
  std::vector<std::string> written;
  auto chart = [&](const std::string& suffix, render::ChartSpec spec) {
    const std::string png = prefix + suffix;
    render::render_chart_png(window, spec, 1000, 650, png);
    written.push_back(png);
  };

  if (std::find(names.begin(), names.end(), "impactor.0.velocity") != names.end()) {
    const std::size_t cV = column("impactor.0.velocity");
    const auto speed = [&](const std::vector<std::string>& r) {  // |v| [m/s] from "[vx, vy(, vz)]" in cm/s
      std::string t = r[cV];
      for (char& c : t)
        if (c == '[' || c == ']' || c == ',') c = ' ';
      std::stringstream ss(t);
      double v2 = 0.0;
      for (double c; ss >> c;) v2 += c * c;
      return std::sqrt(v2) / 100.0;
    };
    std::map<std::pair<int, int>, std::vector<const std::vector<std::string>*>> by_law;
    for (const auto& r : rows) by_law[{static_cast<int>(num(r, "p")), static_cast<int>(num(r, "q"))}].push_back(&r);
    std::vector<render::Series> pieces, largest, tau, nm;
    for (auto& [pq, list] : by_law) {
      std::sort(list.begin(), list.end(), [&](auto* a, auto* b) { return speed(*a) < speed(*b); });
      const std::string law = "(" + std::to_string(pq.first) + "," + std::to_string(pq.second) + ")";
      render::Series n{law, {}, {}}, big{law, {}, {}}, t{law, {}, {}, true};
      for (const auto* r : list) {
        const double v = speed(*r);
        n.x.push_back(v), n.y.push_back(num(*r, "fragments_2plus"));
        big.x.push_back(v), big.y.push_back(num(*r, "largest_mass_fraction"));
        if (std::isfinite(num(*r, "tau"))) t.x.push_back(0.5 * std::pow(100.0 * v, 2)), t.y.push_back(num(*r, "tau"));
      }
      pieces.push_back(n), largest.push_back(big), tau.push_back(t);
      // n(m) of this law's fastest case with a fit, from its fragment_sizes.csv, and the fitted slope
      for (auto it = list.rbegin(); it != list.rend(); ++it) {
        const double exponent = num(**it, "tau"), m_min = num(**it, "tau_m_min_g");
        if (!std::isfinite(exponent)) continue;
        std::ifstream sizes(fs::path(dir) / (**it)[column("case")] / "fragment_sizes.csv");
        std::string line;
        std::getline(sizes, line);
        const int colour = static_cast<int>(pieces.size()) - 1;  // this law's colour in the other charts
        render::Series data{law + " at " + std::to_string(static_cast<long>(speed(**it))) + " m/s", {}, {}, true, colour};
        for (; std::getline(sizes, line);) {
          const auto c = csv_cells(line);
          if (c.size() < 5 || cell_number(c[2]) <= 0) continue;
          data.x.push_back(std::sqrt(cell_number(c[0]) * cell_number(c[1])));  // the bin's geometric centre
          data.y.push_back(cell_number(c[4]));
        }
        if (data.x.empty()) break;
        // the law through the data at the first bin at or above m_min
        std::size_t k = 0;
        while (k + 1 < data.x.size() && data.x[k] < m_min) ++k;
        char label[64];
        std::snprintf(label, sizeof label, "%s fit: tau = %.2f", law.c_str(), exponent);
        render::Series fit{label, {}, {}, false, colour};
        for (double m = data.x[k]; m <= data.x.back() * 1.01; m *= 1.5)
          fit.x.push_back(m), fit.y.push_back(data.y[k] * std::pow(m / data.x[k], -exponent));
        nm.push_back(data), nm.push_back(fit);
        break;
      }
    }
    const std::string where = " (" + std::to_string(rows.size()) + " cases)";
    chart("_pieces.png", {"Pieces of >= 2 particles against impact speed" + where, "impact speed [m/s]",
                                 "pieces of >= 2 particles", true, true, pieces});
    chart("_largest.png", {"Largest piece against impact speed: the transition" + where, "impact speed [m/s]",
                                  "largest piece [fraction of the mass]", true, false, largest});
    chart("_tau.png", {"Mass exponent tau of n(m) ~ m^-tau against impact energy" + where,
                              "impact energy per unit mass v^2/2 [erg/g]", "tau (maximum likelihood)", true, false, tau});
    if (!nm.empty())
      chart("_nm.png", {"Fragment mass distribution n(m), fastest case of each law", "fragment mass m [g]",
                               "n(m) [fragments per g]", true, true, nm});
  } else {
    std::vector<const std::vector<std::string>*> by_e;
    for (const auto& r : rows) by_e.push_back(&r);
    std::sort(by_e.begin(), by_e.end(), [&](auto* a, auto* b) { return num(*a, "E_GPa") < num(*b, "E_GPa"); });
    render::Series onset{"first broken bond", {}, {}}, sep{"separation (2 pieces >= 5 % of the mass)", {}, {}},
        frags{"fragments of >= 2 particles", {}, {}, true};
    for (const auto* r : by_e) {
      const double E = num(*r, "E_GPa");
      if (num(*r, "onset_s") > 0) onset.x.push_back(E), onset.y.push_back(num(*r, "onset_s") * 1e3);
      if (num(*r, "separation_s") > 0) sep.x.push_back(E), sep.y.push_back(num(*r, "separation_s") * 1e3);
      frags.x.push_back(E), frags.y.push_back(num(*r, "fragments_2plus"));
    }
    chart("_times.png", {"Slit plate over (p,q): when it breaks (" + std::to_string(rows.size()) + " pairs)",
                         "Young's modulus E [GPa] of the (p,q) material", "time [ms]", false, false, {onset, sep}});
    render::ChartSpec counts{"Slit plate over (p,q): pieces at the end", "Young's modulus E [GPa] of the (p,q) material",
                             "pieces of >= 2 particles", false, false, {frags}};
    counts.integer_y = true;
    chart("_fragments.png", counts);
  }
  std::string list;
  for (const auto& w : written) list += (list.empty() ? "" : ", ") + w;
  std::printf("wrote %s from %zu completed cases (%ld not completed, left out)\n", list.c_str(), rows.size(), skipped);
}

// `pmfrag study scale-figures SCALE_CSV`: what bench/scale.sh measured, as log-log charts against the particle
// count, one curve per dimension: the wall time per particle-step (flat = cost in proportion to N) and the peak
// resident bytes per particle.
void scale_figures(const std::string& csv_path, const std::string& prefix) {
  std::ifstream in(csv_path);
  if (!in) throw UsageError(csv_path + ": not found (run bench/scale.sh first)");
  std::string header;
  std::getline(in, header);
  const std::vector<std::string> names = csv_cells(header);
  auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw std::runtime_error(csv_path + ": no column '" + name + "'");
    return static_cast<std::size_t>(it - names.begin());
  };
  const std::size_t cDim = column("dim"), cN = column("particles"), cNs = column("ns_per_particle_step"),
                    cRss = column("peak_rss_bytes_per_particle"), cProc = column("processor");
  std::map<std::string, render::Series> cost, memory;
  std::string processor;
  long line_no = 1;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (line.empty()) continue;
    const auto cells = csv_cells(line);
    if (cells.size() != names.size())
      throw std::runtime_error(csv_path + ":" + std::to_string(line_no) + ": " + std::to_string(cells.size()) +
                               " cells, the header has " + std::to_string(names.size()));
    const std::string name = cells[cDim] + "-D";
    const double n = cell_number(cells[cN]);
    cost[name].name = name, memory[name].name = name;
    cost[name].x.push_back(n), cost[name].y.push_back(cell_number(cells[cNs]));
    memory[name].x.push_back(n), memory[name].y.push_back(cell_number(cells[cRss]));
    processor = cells[cProc];
  }
  if (cost.empty()) throw std::runtime_error(csv_path + ": no rows");
  auto draw = [&](const std::map<std::string, render::Series>& by_dim, const std::string& title,
                  const std::string& y_label, const std::string& suffix) {
    render::ChartSpec chart;
    chart.title = title + " (" + processor + ")";
    chart.x_label = "particles";
    chart.y_label = y_label;
    chart.log_x = chart.log_y = true;
    for (const auto& [name, series] : by_dim) chart.series.push_back(series);
    render::HeadlessWindow window(1000, 700);
    render::render_chart_png(window, chart, 1000, 700, prefix + suffix);
    return prefix + suffix;
  };
  const std::string a = draw(cost, "Wall time per particle-step against size", "ns per particle-step", "_cost.png");
  const std::string b = draw(memory, "Peak resident memory per particle against size", "bytes per particle", "_memory.png");
  std::printf("wrote %s and %s\n", a.c_str(), b.c_str());
}

}  // namespace

void add_study_command(CLI::App& app) {
  auto* study = app.add_subcommand("study", "Comparative studies: accuracy against wall time, sweep charts, the paper's parameter figures");
  study->require_subcommand(1);
  auto o = std::make_shared<StudyCli>();
  auto* acc = study->add_subcommand(
      "accuracy", "Run SCENE at several dt and r0; write accuracy.csv and a Pareto chart (error vs wall time)");
  acc->add_option("scene", o->scene, "Scene file (TOML)")->required()->check(CLI::ExistingFile);
  acc->add_option("--out", o->out, "Folder for the runs, accuracy.csv and accuracy.png")->required();
  acc->add_option("--dt", o->dts, "Time steps [s], comma-separated (default 1e-8,2e-8,5e-8,1e-7,2e-7,0.9 x limit)");
  acc->add_option("--r0", o->r0s, "Lattice spacings [cm] (default 0.4,0.2,0.1; not for the Greenspan mesh)");
  acc->add_option("--set", o->set, "Override a scene key for every run, e.g. --set time.end=1.2e-2");
  acc->add_flag("--reuse", o->reuse, "Reuse runs already in OUT with the same scene and overrides (wall times as recorded)");
  acc->add_option("--knobs", o->knobs, "Which knobs to turn: dt, r0, precision (float bond sweeps at each dt; needs dt) (default dt,r0)");
  acc->add_option("--png", o->png, "Where to write the chart (default OUT/accuracy.png)");
  acc->add_option("--threads", o->threads, "OpenMP threads per run (default: all cores)");
  acc->callback([o] { study_accuracy(*o); });
  auto dir = std::make_shared<std::pair<std::string, std::string>>();
  auto* fig = study->add_subcommand("sweep-figures", "Charts of a sweep: over (p,q), break times and pieces against E; over impact speeds, pieces, the largest piece and tau against speed, n(m)");
  fig->add_option("sweep_dir", dir->first, "Folder holding sweep.csv")->required();
  fig->add_option("--prefix", dir->second, "PNG path prefix (default SWEEP_DIR/sweep): PREFIX_times.png, PREFIX_fragments.png, or over impact speeds PREFIX_{pieces,largest,tau,nm}.png");
  fig->callback([dir] { sweep_figures(dir->first, dir->second.empty() ? dir->first + "/sweep" : dir->second); });
  auto scale = std::make_shared<std::pair<std::string, std::string>>();
  auto* sc = study->add_subcommand("scale-figures", "Charts of bench/scale.sh's table: ns per particle-step and peak bytes per particle against N");
  sc->add_option("scale_csv", scale->first, "The table bench/scale.sh wrote (gallery/scale.csv)")->required();
  sc->add_option("--prefix", scale->second, "PNG path prefix (default: the CSV's path without .csv): PREFIX_cost.png, PREFIX_memory.png");
  sc->callback([scale] {
    std::string prefix = scale->second;
    if (prefix.empty()) prefix = (fs::path(scale->first).parent_path() / fs::path(scale->first).stem()).string();
    scale_figures(scale->first, prefix);
  });
  add_study_figures_command(*study);
  add_study_modulus_command(*study);
}

}  // namespace pmfrag::app
