#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag scene SCENE`: check a scene and describe what it builds; optionally write it as a
/// LAMMPS data file for an independent run of the same particles and bonds.
void add_scene_command(CLI::App& app);
}  // namespace pmfrag::app
