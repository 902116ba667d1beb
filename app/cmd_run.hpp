#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag run SCENE --out DIR`: simulate a scene and write DIR/trajectory.h5.
void add_run_command(CLI::App& app);
}  // namespace pmfrag::app
