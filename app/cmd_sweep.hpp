#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag sweep SPEC --out DIR`: a base scene over (p,q) pairs and other keys, one folder per case.
void add_sweep_command(CLI::App& app);
}  // namespace pmfrag::app
