#pragma once
#include <CLI/CLI.hpp>

namespace pmfrag::app {
/// Registers `pmfrag lammps SCENE --out DIR`: the scene as a LAMMPS deck (DIR/in.lammps and its data), for runs
/// too big or too slow for one machine; `pmfrag import` reads the run back.
void add_lammps_command(CLI::App& app);
}  // namespace pmfrag::app
