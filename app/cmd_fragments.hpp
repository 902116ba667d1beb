#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag fragments RUN_DIR`: broken bonds clustered into fragments, per frame and at the end.
void add_fragments_command(CLI::App& app);
}  // namespace pmfrag::app
