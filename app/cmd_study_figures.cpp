// `pmfrag study figures --out DIR`: the paper's parameter figures, regenerated from the material model
// (Sec. 5.1, Eqs. 21-34, with physics.md's corrections): Fig. 3 (E and strength over the (p,q) grid),
// Fig. 7 (potential and force of the three pairs), Fig. 8 (E against r0 at a fixed block), Figs. 10-11 (E as
// the block grows in x, and in all directions). Each figure is a PNG and a CSV of what it plots. Wiring only.
#include "cmd_study.hpp"

#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/model/material.hpp"
#include "pmfrag/render/charts.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <sstream>
#include <string>
#include <vector>

namespace pmfrag::app {

namespace {

namespace fs = std::filesystem;

// The pairs of the paper's Figs. 9-10: three with p = 1 (whose E grows with r0) and the three of Table 1.
const std::vector<std::array<int, 2>> fig_pairs{{1, 5}, {1, 10}, {1, 14}, {3, 5}, {5, 10}, {7, 14}};

std::string pq_name(int p, int q) { return "(" + std::to_string(p) + "," + std::to_string(q) + ")"; }

// A table filled while a figure is computed, then written whole (write_file_atomically) by commit().
struct Table {
  fs::path path;
  std::ostringstream text;
  explicit Table(fs::path p) : path(std::move(p)) { text.precision(8); }
  template <class T>
  Table& operator<<(const T& v) {
    text << v;
    return *this;
  }
  void commit() const {
    write_file_atomically(path, [&](std::ostream& o) { o << text.str(); });
  }
};

void figures(const std::string& out) {
  const fs::path dir(out);
  make_folder(dir);
  render::HeadlessWindow window(900, 650);
  std::vector<std::string> wrote;
  auto png = [&](const std::string& name) {
    wrote.push_back(name);
    return (dir / name).string();
  };

  // Fig. 3: E and the tensile strength over p = 1..14, q = 2..15 (q > p), r0 = 0.2 cm, the paper's block.
  {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    render::HeatmapSpec E{"Fig. 3(a): Young's modulus over (p,q), r0 = 0.2 cm", "p", "q", "E [GPa]", 1, 2, 14, 14,
                          std::vector<double>(14 * 14, nan)};
    render::HeatmapSpec S{"Fig. 3(b): tensile strength over (p,q) (Table 1 convention)", "p", "q", "sigma_TS [MN/m2]",
                          1, 2, 14, 14, std::vector<double>(14 * 14, nan)};
    Table csv(dir / "fig3.csv");
    csv << "p,q,E_GPa,sigma_TS_paper_MNm2,sigma_TS_MNm2\n";
    for (const auto& [p, q] : fig3_grid()) {
      const Material m = derive_material(p, q, 0.2);
      const std::size_t cell = static_cast<std::size_t>(q - 2) * 14 + static_cast<std::size_t>(p - 1);
      E.values[cell] = m.E_GPa;
      S.values[cell] = m.sigma_TS_paper_MNm2;
      csv << p << "," << q << "," << m.E_GPa << "," << m.sigma_TS_paper_MNm2 << "," << m.sigma_TS_MNm2 << "\n";
    }
    csv.commit();
    render::render_heatmap_png(window, E, 800, 700, png("fig3_E.png"));
    render::render_heatmap_png(window, S, 800, 700, png("fig3_strength.png"));
  }

  // Fig. 7: the pair potential and force of the three Table 1 pairs, from 0.95 r0 to D = 1.7 r0. Plotted in
  // 1e8 erg and 1e9 dyne: VTK 9.1's charts misdraw curves whose y values are ~1e10 times their x values.
  {
    const double r0 = 0.2;
    std::vector<render::Series> phi, force;
    Table csv(dir / "fig7.csv");
    csv << "p,q,r_cm,potential_erg,force_dyne\n";
    for (const auto& [p, q] : std::vector<std::array<int, 2>>{{3, 5}, {5, 10}, {7, 14}}) {
      const Material m = derive_material(p, q, r0);
      render::Series a{pq_name(p, q), {}, {}}, b{pq_name(p, q), {}, {}};
      for (int k = 0; k <= 160; ++k) {
        const double r = r0 * (0.95 + 0.75 * k / 160.0);
        a.x.push_back(r), a.y.push_back(m.law.potential(r) * 1e-8);
        b.x.push_back(r), b.y.push_back(m.law.force(r) * 1e-9);
        csv << p << "," << q << "," << r << "," << m.law.potential(r) << "," << m.law.force(r) << "\n";
      }
      phi.push_back(a), force.push_back(b);
    }
    csv.commit();
    render::render_chart_png(window, {"Fig. 7(a): pair potential, r0 = 0.2 cm", "r [cm]", "potential [1e8 erg]", false, false, phi},
                             900, 650, png("fig7_potential.png"));
    render::render_chart_png(window,
                             {"Fig. 7(b): pair force (positive = repulsive), r0 = 0.2 cm", "r [cm]", "force [1e9 dyne]", false,
                              false, force},
                             900, 650, png("fig7_force.png"));
  }

  // Fig. 8: E against r0 = 0.1..0.5 cm for the paper's block (8 x 11.43 x 3.1 cm).
  {
    std::vector<render::Series> curves;
    Table csv(dir / "fig8.csv");
    csv << "p,q,r0_cm,nodes,E_GPa\n";
    for (const auto& [p, q] : fig_pairs) {
      render::Series s{pq_name(p, q), {}, {}};
      for (int k = 0; k <= 40; ++k) {
        const double r0 = 0.1 + 0.01 * k;
        const Material m = derive_material(p, q, r0);
        s.x.push_back(r0), s.y.push_back(m.E_GPa);
        csv << p << "," << q << "," << r0 << "," << m.N << "," << m.E_GPa << "\n";
      }
      curves.push_back(s);
    }
    csv.commit();
    render::render_chart_png(window,
                             {"Fig. 8: E against r0, block 8 x 11.43 x 3.1 cm", "r0 [cm]", "E [GPa]", false, false, curves},
                             900, 650, png("fig8_E_vs_r0.png"));
  }

  // Fig. 10: the block grows in x (n r0), 25 r0 in y and z; r0 = 0.2 cm.
  {
    const double r0 = 0.2;
    std::vector<render::Series> curves;
    Table csv(dir / "fig10.csv");
    csv << "p,q,n_x,E_GPa\n";
    for (const auto& [p, q] : fig_pairs) {
      render::Series s{pq_name(p, q), {}, {}};
      for (int n = 1; n <= 60; ++n) {
        const Material m = derive_material(p, q, r0, Block{n * r0, 25 * r0, 25 * r0});
        s.x.push_back(n), s.y.push_back(m.E_GPa);
        csv << p << "," << q << "," << n << "," << m.E_GPa << "\n";
      }
      curves.push_back(s);
    }
    csv.commit();
    render::render_chart_png(window,
                             {"Fig. 10: E as the block grows in x (25 r0 in y and z), r0 = 0.2 cm",
                              "block length in x [units of r0]", "E [GPa]", false, false, curves},
                             900, 650, png("fig10_E_vs_x.png"));
  }

  // Fig. 11: (7,14), the block grown in all directions: E against a uniform n, and over (n_x, n_y) at n_z = 25.
  {
    const double r0 = 0.2;
    render::Series s{"(7,14), n r0 in x, y and z", {}, {}};
    Table csv(dir / "fig11.csv");
    csv << "n_x,n_y,n_z,E_GPa\n";
    for (int n = 1; n <= 60; ++n) {
      const double E = derive_material(7, 14, r0, Block{n * r0, n * r0, n * r0}).E_GPa;
      s.x.push_back(n), s.y.push_back(E);
      csv << n << "," << n << "," << n << "," << E << "\n";
    }
    render::render_chart_png(window,
                             {"Fig. 11: E of (7,14) as the block grows in all directions, r0 = 0.2 cm",
                              "block edge [units of r0]", "E [GPa]", false, false, {s}},
                             900, 650, png("fig11_E_uniform.png"));
    render::HeatmapSpec map{"Fig. 11: E of (7,14) over the block's x and y lengths (z: 25 r0)",
                            "block length in x [units of r0]", "block length in y [units of r0]", "E [GPa]", 1, 1, 40, 40,
                            {}};
    for (int ny = 1; ny <= 40; ++ny)
      for (int nx = 1; nx <= 40; ++nx) {
        const double E = derive_material(7, 14, r0, Block{nx * r0, ny * r0, 25 * r0}).E_GPa;
        map.values.push_back(E);
        csv << nx << "," << ny << ",25," << E << "\n";
      }
    csv.commit();
    render::render_heatmap_png(window, map, 800, 700, png("fig11_E_xy.png"));
  }
  std::printf("wrote to %s:", dir.c_str());
  for (const auto& w : wrote) std::printf(" %s", w.c_str());
  std::printf("\n  and the data behind them: fig3.csv fig7.csv fig8.csv fig10.csv fig11.csv\n");
}

}  // namespace

void add_study_figures_command(CLI::App& study) {
  auto out = std::make_shared<std::string>("gallery");
  auto* cmd = study.add_subcommand("figures", "The paper's parameter figures (Figs. 3, 7, 8, 10, 11) from the material model");
  cmd->add_option("--out", *out, "Folder for the PNGs and CSVs (default gallery)");
  cmd->callback([out] { figures(*out); });
}

}  // namespace pmfrag::app
