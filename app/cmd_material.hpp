#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag material`: the material model of Sec. 5.1 (Table 1, Fig. 3 grid, Eq. 15 limits).
void add_material_command(CLI::App& app);
}  // namespace pmfrag::app
