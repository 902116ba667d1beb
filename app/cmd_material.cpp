#include "cmd_material.hpp"

#include "parse.hpp"
#include "pmfrag/model/material.hpp"

#include <array>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag::app {

namespace {

struct MaterialOptions {
  std::vector<std::string> pq;
  double r0 = 0.2;
  std::string block = "8,11.43,3.1";
  double rmin_r0 = 0.1;
  bool json = false;
  bool grid = false;
};

struct Row {
  const char* key;    // JSON key: the quantity with its unit
  const char* label;  // human label
  double (*get)(const Material&, double rmin_r0);
  const char* fmt;
};

const Row rows[] = {
    {"r0_cm", "r0 [cm]", [](const Material& m, double) { return m.r0_cm; }, "%.6g"},
    {"imax", "imax", [](const Material& m, double) { return double(m.imax); }, "%.0f"},
    {"jmax", "jmax", [](const Material& m, double) { return double(m.jmax); }, "%.0f"},
    {"kmax", "kmax", [](const Material& m, double) { return double(m.kmax); }, "%.0f"},
    {"N", "N (Eq. 27)", [](const Material& m, double) { return m.N; }, "%.0f"},
    {"Nstar", "N* (Eq. 21)", [](const Material& m, double) { return m.Nstar; }, "%.7e"},
    {"mass_g", "m [g] (Eq. 28)", [](const Material& m, double) { return m.mass_g; }, "%.6g"},
    {"phi0_erg", "phi(r0) [erg]", [](const Material& m, double) { return m.phi0_erg; }, "%.6e"},
    {"G", "G [dyne cm^p]", [](const Material& m, double) { return m.law.G; }, "%.6e"},
    {"H", "H [dyne cm^q]", [](const Material& m, double) { return m.law.H; }, "%.6e"},
    {"S0_dyne_per_cm", "S0 [dyne/cm]", [](const Material& m, double) { return m.S0_dyne_per_cm; }, "%.6e"},
    {"E_GPa", "E [GPa] (Eq. 26)", [](const Material& m, double) { return m.E_GPa; }, "%.7g"},
    {"r_d_cm", "r_d [cm]", [](const Material& m, double) { return m.r_d_cm; }, "%.6g"},
    {"peak_force_dyne", "|F(r_d)| [dyne]", [](const Material& m, double) { return m.peak_force_dyne; }, "%.6e"},
    {"sigma_TS_paper_MNm2", "sigma_TS, paper conv. [MN/m^2]",
     [](const Material& m, double) { return m.sigma_TS_paper_MNm2; }, "%.6g"},
    {"sigma_TS_MNm2", "sigma_TS, consistent [MN/m^2]", [](const Material& m, double) { return m.sigma_TS_MNm2; },
     "%.6g"},
    {"dt_max_stretch_s", "dt max, stretch [s] (Eq. 15)",
     [](const Material& m, double) { return m.dt_max_stretch_s; }, "%.4e"},
    {"r_min_cm", "r_min [cm]", [](const Material& m, double f) { return f * m.r0_cm; }, "%.6g"},
    {"dt_max_impact_s", "dt max, impact at r_min [s]",
     [](const Material& m, double f) { return dt_limit_impact(m.law, m.mass_g, f * m.r0_cm); }, "%.4e"},
};

void print_table(const std::vector<Material>& mats, double rmin_r0) {
  std::printf("%-32s", "(p,q)");
  for (const auto& m : mats) std::printf(" %16s", ("(" + std::to_string(m.p) + "," + std::to_string(m.q) + ")").c_str());
  std::printf("\n");
  for (const auto& row : rows) {
    std::printf("%-32s", row.label);
    for (const auto& m : mats) {
      char buf[64];
      std::snprintf(buf, sizeof buf, row.fmt, row.get(m, rmin_r0));
      std::printf(" %16s", buf);
    }
    std::printf("\n");
  }
  std::printf("block %.6g x %.6g x %.6g cm; sigma_TS 'paper conv.' reproduces Table 1 (N = 1/r_d^2, x1e-8);\n"
              "'consistent' is the same stress in correct units (x1e-7). See docs/physics.md.\n",
              mats.front().block.A, mats.front().block.B, mats.front().block.C);
}

void print_json(const std::vector<Material>& mats, double rmin_r0) {
  std::printf("[\n");
  for (std::size_t i = 0; i < mats.size(); ++i) {
    const auto& m = mats[i];
    std::printf("  {\"p\": %d, \"q\": %d, \"block_cm\": [%.10g, %.10g, %.10g]", m.p, m.q, m.block.A, m.block.B,
                m.block.C);
    for (const auto& row : rows) std::printf(", \"%s\": %.10g", row.key, row.get(m, rmin_r0));
    std::printf("}%s\n", i + 1 < mats.size() ? "," : "");
  }
  std::printf("]\n");
}

void print_grid(double r0, const Block& block) {
  std::printf("p,q,G,H,E_GPa,sigma_TS_paper_MNm2,sigma_TS_MNm2,r_d_cm,mass_g,dt_max_stretch_s\n");
  for (auto [p, q] : fig3_grid()) {
    const Material m = derive_material(p, q, r0, block);
    std::printf("%d,%d,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n", p, q, m.law.G, m.law.H, m.E_GPa,
                m.sigma_TS_paper_MNm2, m.sigma_TS_MNm2, m.r_d_cm, m.mass_g, m.dt_max_stretch_s);
  }
}

void run(const MaterialOptions& o) {
  if (!(o.r0 > 0.0)) throw UsageError("--r0: must be a positive length in cm (got " + std::to_string(o.r0) + ")");
  if (!(o.rmin_r0 > 0.0) || o.rmin_r0 > 1.0) throw UsageError("--rmin-r0: must be in (0, 1]");
  const auto b = parse_numbers("--block", o.block, 3);
  const Block block{b[0], b[1], b[2]};
  if (!(block.A >= o.r0 && block.B >= o.r0 && block.C >= o.r0))
    throw UsageError("--block: every side must be at least r0 = " + std::to_string(o.r0) + " cm");
  if (o.grid) {
    print_grid(o.r0, block);
    return;
  }
  std::vector<std::array<int, 2>> pairs;
  if (o.pq.empty()) pairs = {{3, 5}, {5, 10}, {7, 14}};  // the paper's three (Table 1)
  for (const auto& s : o.pq) {
    const auto v = parse_ints("--pq", s, 2);
    try {
      validate_exponents(v[0], v[1]);
    } catch (const std::invalid_argument& e) {
      throw UsageError("--pq " + s + ": " + e.what());
    }
    pairs.push_back({v[0], v[1]});
  }
  std::vector<Material> mats;
  for (auto [p, q] : pairs) mats.push_back(derive_material(p, q, o.r0, block));
  if (o.json)
    print_json(mats, o.rmin_r0);
  else
    print_table(mats, o.rmin_r0);
}

}  // namespace

void add_material_command(CLI::App& app) {
  auto opts = std::make_shared<MaterialOptions>();
  auto* cmd = app.add_subcommand("material",
                                 "Derive the particle-model material from MD copper (Sec. 5.1): G, H, mass, E, "
                                 "tensile strength and the Eq. 15 time-step limits");
  cmd->add_option("--pq", opts->pq,
                  "Exponents p,q of F = -G/r^p + H/r^q (q > p >= 1); repeat for several. "
                  "Default: the paper's 3,5 5,10 7,14")
      ->type_name("P,Q");
  cmd->add_option("--r0", opts->r0, "Lattice spacing r0 in cm (default 0.2)")->type_name("CM");
  cmd->add_option("--block", opts->block, "Block A,B,C in cm that the particles stand for (default 8,11.43,3.1)")
      ->type_name("A,B,C");
  cmd->add_option("--rmin-r0", opts->rmin_r0,
                  "Impact clamp r_min as a fraction of r0 for the impact time-step limit (default 0.1)")
      ->type_name("FRACTION");
  cmd->add_flag("--json", opts->json, "Print JSON (keys carry units: E_GPa, mass_g, dt_max_stretch_s, ...)");
  cmd->add_flag("--grid", opts->grid, "Print the Fig. 3 grid (p = 1..14, q = 2..15, q > p) as CSV");
  cmd->callback([opts] { run(*opts); });
}

}  // namespace pmfrag::app
