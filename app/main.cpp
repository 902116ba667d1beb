// pmfrag: particle modeling of dynamic fracture and fragmentation. This file only wires subcommands.
#include "cmd_export.hpp"
#include "cmd_fragments.hpp"
#include "cmd_lammps.hpp"
#include "cmd_material.hpp"
#include "cmd_render.hpp"
#include "cmd_run.hpp"
#include "cmd_scene.hpp"
#include "cmd_study.hpp"
#include "cmd_sweep.hpp"
#include "parse.hpp"
#include "process.hpp"
#include "pmfrag/io/h5md.hpp"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  // A write past a file-size limit (ulimit -f) then fails with EFBIG, which the writers report with the file's
  // name, instead of killing the process before it can say anything.
  std::signal(SIGXFSZ, SIG_IGN);
  pmfrag::app::exit_with_worker_parent();
  CLI::App app{
      "pmfrag - particle modeling (Wang & Ostoja-Starzewski 2005, after Greenspan) of dynamic fracture and "
      "fragmentation: material model, simulation, fragments, ParaView export and figures."};
  app.require_subcommand(1);
  app.fallthrough();  // --verbose may come after the subcommand too
  app.add_flag_callback("--verbose", [] { pmfrag::show_library_diagnostics(true); },
                        "Print the libraries' own error reports (HDF5's stack) beside pmfrag's one-line messages");
  pmfrag::app::add_material_command(app);
  pmfrag::app::add_run_command(app);
  pmfrag::app::add_scene_command(app);
  pmfrag::app::add_lammps_command(app);
  pmfrag::app::add_fragments_command(app);
  pmfrag::app::add_export_command(app);
  pmfrag::app::add_render_command(app);
  pmfrag::app::add_study_command(app);
  pmfrag::app::add_sweep_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "pmfrag: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const pmfrag::app::UsageError& e) {
    std::fprintf(stderr, "pmfrag: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmfrag: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
