#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag study accuracy SCENE`: what the time step and the lattice spacing buy, against wall time.
void add_study_command(CLI::App& app);
}  // namespace pmfrag::app
