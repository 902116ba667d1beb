#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag study accuracy SCENE`: what the time step and the lattice spacing buy, against wall time.
void add_study_command(CLI::App& app);
/// Registers `pmfrag study figures`: the paper's parameter figures from the material model (cmd_study_figures.cpp).
void add_study_figures_command(CLI::App& study);
/// Registers `pmfrag study modulus`: a virtual tensile test against Eq. (26) (cmd_study_modulus.cpp).
void add_study_modulus_command(CLI::App& study);
}  // namespace pmfrag::app
