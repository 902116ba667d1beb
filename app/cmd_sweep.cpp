// `pmfrag sweep SPEC.toml --out DIR`: every case of a sweep spec in its own folder (trajectory, fragments,
// summary), run by a local pool of worker processes (`pmfrag run` then `pmfrag fragments`, so a case that
// crashes takes nothing else down), and one sweep.csv. Finished cases are skipped on rerun; a failed case is
// recorded with its error and the others go on. Wiring only.
#include "cmd_sweep.hpp"

#include "parse.hpp"
#include "mpi_world.hpp"
#include "process.hpp"
#include "run_files.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/run/run.hpp"
#include "pmfrag/body/scene.hpp"
#include "pmfrag/run/sweep.hpp"
#include "pmfrag/body/system.hpp"

#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <set>
#include <thread>

namespace pmfrag::app {

namespace {

namespace fs = std::filesystem;

// summary.json as sweep.csv cells: onset and separation times, pieces of >= 2 particles and of >= 1 % of the
// mass, the largest fraction, then all pieces, single particles, the second-largest fraction, tau, its
// interval, how many pieces it fitted and from what mass (empty where the fit gave none, or the case has no
// summary).
std::string summary_cells(const std::string& summary) {
  const nlohmann::json j = nlohmann::json::parse(summary, nullptr, false);
  auto cell = [](const nlohmann::json& obj, const char* key) -> std::string {
    if (!obj.is_object() || !obj.contains(key) || !obj[key].is_number()) return "";
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", obj[key].get<double>());
    return b;
  };
  std::string out = cell(j, "onset_time_s") + "," + cell(j, "separation_time_s") + "," + cell(j, "fragments_2plus") +
                    "," + cell(j, "fragments_1pct_mass") + "," + cell(j, "largest_mass_fraction") + "," +
                    cell(j, "fragments") + "," + cell(j, "single_particles") + "," +
                    cell(j, "second_largest_mass_fraction");
  const nlohmann::json d = j.is_object() && j.contains("distribution") ? j["distribution"] : nlohmann::json();
  const nlohmann::json ci = d.is_object() && d.contains("exponent_ci") ? d["exponent_ci"] : nlohmann::json();
  const auto bound = [&](std::size_t k) {
    return ci.is_array() && ci.size() == 2 ? cell(nlohmann::json{{"v", ci[k]}}, "v") : std::string();
  };
  return out + "," + cell(d, "exponent") + "," + bound(0) + "," + bound(1) + "," + cell(d, "fragments_fitted") + "," +
         cell(d, "m_min_g");
}

struct SweepCli {
  std::string spec, out;
  std::vector<std::string> pairs, set;
  int jobs = 0;
};

// run.json read back; a missing or unreadable one is a run that did not finish.
RunResult run_record(const fs::path& dir) {
  try {
    return read_run_record((dir / "run.json").string());
  } catch (const std::runtime_error&) {
    return RunResult{};
  }
}

bool finished(const fs::path& dir) { return fs::exists(dir / "summary.json") && run_record(dir).completed; }

// Why a case failed, in its folder (error.txt) and on the terminal.
void record_failure(const fs::path& dir, const std::string& name, int status, const std::string& who) {
  std::string why = run_record(dir).message;
  if (why.empty()) {  // the last line the worker printed
    const std::string log = slurp(dir / "log.txt");
    auto end = log.find_last_not_of('\n');
    auto from = end == std::string::npos ? 0 : log.rfind('\n', end);
    why = end == std::string::npos ? "no output" : log.substr(from == std::string::npos ? 0 : from + 1, end - from);
  }
  if (WIFSIGNALED(status)) why = "killed by signal " + std::to_string(WTERMSIG(status)) + "; " + why;
  write_file_atomically(dir / "error.txt", [&](std::ostream& f) { f << why << "\n"; });
  std::printf("%s  %-24s FAILED: %s\n", who.c_str(), name.c_str(), why.c_str());
}

void sweep(const SweepCli& o) {
  MpiWorld world;  // one rank unless mpirun started us
  const bool lead = world.rank() == 0;
  SweepSpec spec = read_sweep_spec(o.spec);
  if (!o.pairs.empty()) {
    std::vector<std::array<int, 2>> keep;
    for (const auto& text : o.pairs) {
      const auto pq = parse_ints("--pairs", text, 2);
      keep.push_back({pq[0], pq[1]});
    }
    spec.pairs = keep;
  }
  spec.set.insert(spec.set.end(), o.set.begin(), o.set.end());
  const Scene base = read_scene(spec.base, spec.set);
  const double r0 = build_system(base).r0;
  const auto cases = sweep_cases(spec, base.phases.size());
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // Under mpirun each rank runs one case at a time with its share of the node's cores; alone, a local pool.
  const int jobs = world.size() > 1 ? 1 : o.jobs > 0 ? o.jobs : std::min<int>(cores, static_cast<int>(cases.size()));
  const int threads = std::max(1, cores / std::max(1, world.size() > 1 ? world.local_size() : jobs));
  const std::string who = world.size() > 1 ? "[rank " + std::to_string(world.rank()) + "]" : "";
  if (lead) {
    make_folder(o.out);
    if (world.size() > 1)
      std::printf("sweep %s: %zu cases of %s, %d MPI ranks x %d threads, cases handed out as ranks free up\n",
                  o.spec.c_str(), cases.size(), spec.base.c_str(), world.size(), threads);
    else
      std::printf("sweep %s: %zu cases of %s, %d worker processes x %d threads\n", o.spec.c_str(), cases.size(),
                  spec.base.c_str(), jobs, threads);
  }

  std::vector<std::size_t> todo;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const fs::path dir = fs::path(o.out) / cases[c].name;
    if (finished(dir)) {
      if (lead) std::printf("  %-24s finished before: skipped\n", cases[c].name.c_str());
    } else {
      if (lead) {
        fs::remove_all(dir);
        make_folder(dir);
      }
      todo.push_back(c);
    }
  }
  std::fflush(stdout);
  world.barrier();  // the case folders are ready before any rank starts
  become_worker_parent();
  std::map<pid_t, std::pair<std::size_t, int>> running;  // pid -> (case, stage: 1 run, 2 fragments)
  std::size_t next = 0;
  auto start = [&](std::size_t c, int stage) -> pid_t {
    const fs::path dir = fs::path(o.out) / cases[c].name;
    std::vector<std::string> args{"pmfrag"};
    if (stage == 1) {
      args.insert(args.end(), {"run", spec.base, "--out", dir.string(), "--force", "-q", "--threads", std::to_string(threads)});
      for (const auto& s : cases[c].overrides) args.insert(args.end(), {"--set", s});
    } else {
      args.insert(args.end(), {"fragments", dir.string()});
    }
    return start_process("/proc/self/exe", args, dir / "log.txt");
  };
  if (world.size() > 1) {
    // Each case start to end (run, then fragments) on whichever rank asks next.
    world.distribute(static_cast<int>(todo.size()), [&](int i) {
      const std::size_t c = todo[static_cast<std::size_t>(i)];
      const fs::path dir = fs::path(o.out) / cases[c].name;
      for (int stage = 1; stage <= 2; ++stage) {
        const pid_t pid = start(c, stage);
        int status = 0;
        ::waitpid(pid, &status, 0);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
          record_failure(dir, cases[c].name, status, who);
          std::fflush(stdout);
          return;
        }
      }
      std::printf("%s  %-24s done\n", who.c_str(), cases[c].name.c_str());
      std::fflush(stdout);
    });
  }
  while (world.size() == 1 && (next < todo.size() || !running.empty())) {
    while (static_cast<int>(running.size()) < jobs && next < todo.size()) {
      const std::size_t c = todo[next++];
      running[start(c, 1)] = {c, 1};
    }
    int status = 0;
    const pid_t pid = ::wait(&status);
    if (pid < 0) break;
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const auto [c, stage] = it->second;
    running.erase(it);
    const fs::path dir = fs::path(o.out) / cases[c].name;
    const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (ok && stage == 1) {
      running[start(c, 2)] = {c, 2};
      continue;
    }
    if (!ok) {
      record_failure(dir, cases[c].name, status, who);
    } else {
      std::printf("  %-24s done\n", cases[c].name.c_str());
    }
    std::fflush(stdout);
  }

  if (!lead) return;  // rank 0 gathers every case's folder into sweep.csv
  const fs::path csv = fs::path(o.out) / "sweep.csv";
  long failed = 0;
  write_file_atomically(csv, [&](std::ostream& f) {
    // A column per varied key after (p,q); the mass distribution's exponent and its interval after the counts.
    f << "case,p,q";
    for (const auto& [key, values] : spec.vary) f << "," << key;
    f << ",E_GPa,sigma_TS_MNm2,dt_s,onset_s,separation_s,fragments_2plus,fragments_1pct_mass,"
         "largest_mass_fraction,fragments,single_particles,second_largest_mass_fraction,tau,tau_ci_low,tau_ci_high,"
         "tau_fragments_fitted,tau_m_min_g,particle_steps_per_s,wall_s,status\n";
    for (const auto& k : cases) {
      const fs::path dir = fs::path(o.out) / k.name;
      const Material m = derive_material(k.p, k.q, r0);
      const RunResult run = run_record(dir);
      const std::string sum = slurp(dir / "summary.json");
      std::string status = "completed";
      if (fs::exists(dir / "error.txt")) {
        status = slurp(dir / "error.txt");
        status.erase(status.find_last_not_of('\n') + 1);
        ++failed;
      } else if (!run.completed) {
        status = "stopped: " + run.message;
      }
      for (char& ch : status)
        if (ch == '"') ch = '\'';
      auto val = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, "%.6g", v);
        return std::string(b);
      };
      f << k.name << "," << k.p << "," << k.q;
      for (const auto& [key, values] : spec.vary)
        for (const auto& item : k.overrides)
          if (item.rfind(key + "=", 0) == 0) {
            std::string v = item.substr(key.size() + 1);
            for (char& ch : v)
              if (ch == '"') ch = '\'';
            f << ",\"" << v << "\"";
          }
      f << "," << val(m.E_GPa) << "," << val(m.sigma_TS_MNm2) << ","
        << val(run.dt) << "," << summary_cells(sum) << "," << val(run.particle_steps_per_s()) << "," << val(run.wall_s)
        << ",\"" << status << "\"\n";
    }
  });
  std::printf("wrote %s: %zu cases, %ld failed\n", csv.c_str(), cases.size(), failed);
  if (failed > 0)  // scripts learn of it; the finished cases stay, and a rerun retries only the failed ones
    throw std::runtime_error(std::to_string(failed) + " of " + std::to_string(cases.size()) + " cases failed (" +
                             csv.string() + " and each one's error.txt say why)");
}

}  // namespace

void add_sweep_command(CLI::App& app) {
  auto o = std::make_shared<SweepCli>();
  auto* cmd = app.add_subcommand("sweep", "Run a base scene over (p,q) pairs and other keys; gather sweep.csv");
  cmd->add_option("spec", o->spec, "Sweep spec (TOML: base, pairs, [set], [vary])")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Folder for the cases and sweep.csv")->required();
  cmd->add_option("--pairs", o->pairs, "Only these pairs, e.g. --pairs 3,5 7,14");
  cmd->add_option("--set", o->set, "Override a scene key in every case");
  cmd->add_option("--jobs", o->jobs, "Worker processes (default: one per core, each with the remaining threads)");
  cmd->callback([o] { sweep(*o); });
}

}  // namespace pmfrag::app
