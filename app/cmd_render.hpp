#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag render RUN_DIR`: PNG frames of a run and figure panels, with no display.
void add_render_command(CLI::App& app);
}  // namespace pmfrag::app
