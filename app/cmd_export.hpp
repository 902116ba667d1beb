#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag export RUN_DIR`: VTU frames and a PVD collection for ParaView.
void add_export_command(CLI::App& app);
}  // namespace pmfrag::app
