// `pmfrag study modulus --out DIR`: a virtual tensile test. A defect-free block of each of the paper's three
// materials is stretched slowly (rows pulled at 20 cm/s, ~20 wave transits to a strain of 2e-3); E is fitted
// from the elastic energy U - U0 = E V eps^2 / 2 and compared with Eq. (26), E = S0 / r0, in 2-D and 3-D;
// the lateral contraction gives the Poisson ratio. Wiring only: the test is studies::tensile_test.
#include "cmd_study.hpp"

#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/studies/tensile.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace pmfrag::app {

namespace {

namespace fs = std::filesystem;

void modulus(const std::string& out, int scale) {
  const fs::path dir(out);
  make_folder(dir);
  std::vector<studies::TensileResult> rows;
  std::printf("%-4s %-7s %9s %12s %12s %8s %8s %9s\n", "dim", "(p,q)", "particles", "E Eq.26 GPa", "E fit GPa",
              "ratio", "Poisson", "fit rms");
  for (int dim : {2, 3})
    for (const auto& [p, q] : std::vector<std::array<int, 2>>{{3, 5}, {5, 10}, {7, 14}}) {
      const studies::TensileResult r = studies::tensile_test(dir, dim, p, q, scale);
      std::printf("%-4s %-7s %9zu %12.4g %12.4g %8.4f %8.3f %9.2e\n", dim == 2 ? "2-D" : "3-D",
                  ("(" + std::to_string(p) + "," + std::to_string(q) + ")").c_str(), r.particles, r.E_eq26, r.E_fit,
                  r.E_fit / r.E_eq26, r.poisson, r.fit_rms);
      std::fflush(stdout);
      rows.push_back(r);
    }
  const fs::path csv = dir / "modulus.csv";
  write_file_atomically(csv, [&](std::ostream& f) {
    f << "dim,p,q,particles,E_eq26_GPa,E_fit_GPa,ratio,poisson,max_strain,fit_rms_rel\n";
    for (const auto& r : rows)
      f << r.dim << "," << r.p << "," << r.q << "," << r.particles << "," << r.E_eq26 << "," << r.E_fit << ","
        << r.E_fit / r.E_eq26 << "," << r.poisson << "," << r.strain << "," << r.fit_rms << "\n";
  });
  std::printf("wrote %s (2-D stresses use a thickness of r0; see docs/accuracy.md, \"Virtual tensile test\")\n",
              csv.c_str());
}

}  // namespace

void add_study_modulus_command(CLI::App& study) {
  auto out = std::make_shared<std::string>();
  auto scale = std::make_shared<int>(1);
  auto* cmd = study.add_subcommand("modulus", "Virtual tensile test: fitted E against Eq. (26) for the three pairs, 2-D and 3-D");
  cmd->add_option("--out", *out, "Folder for the six runs and modulus.csv")->required();
  cmd->add_option("--scale", *scale, "Grow the blocks K times in every direction (size effects; default 1)")
      ->check(CLI::Range(1, 8));
  cmd->callback([out, scale] { modulus(*out, *scale); });
}

}  // namespace pmfrag::app
