#include "cmd_lammps.hpp"

#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/io/lammps.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace pmfrag::app {

namespace {

struct LammpsCli {
  std::string scene, out;
  std::vector<std::string> set;
  bool force = false;
};

void run(const LammpsCli& o) {
  const Scene sc = read_scene(o.scene, o.set);
  const System sys = build_system(sc);
  check_lammps_can_run(sc, sys);  // before the folder is touched
  const std::filesystem::path dir(o.out);
  if (std::filesystem::exists(dir / "in.lammps") && !o.force)
    throw std::runtime_error((dir / "in.lammps").string() + " exists; use --force to overwrite the deck");
  const FolderLock lock(dir);
  const LammpsDeck deck = write_lammps_deck(sc, sys, dir);
  std::printf("wrote the LAMMPS deck %s/in.lammps (%zu particles, %ld steps of %g s, a frame every %ld steps)\n",
              o.out.c_str(), sys.size(), deck.steps, deck.dt, deck.frame_every);
  std::printf("run it:  cd %s && mpirun -np N lmp -in in.lammps\nthen:    pmfrag import %s --out RUN\n", o.out.c_str(),
              o.out.c_str());
}

struct ImportCli {
  std::string deck, out;
  bool force = false;
};

void run_import(const ImportCli& o) {
  const LammpsImport r = import_lammps_run(o.deck, o.out, o.force);
  std::printf("imported %ld frames (steps 0..%ld of %ld) from the LAMMPS run in %s into %s/trajectory.h5%s\n", r.frames,
              r.last_step, r.steps, o.deck.c_str(), o.out.c_str(), r.partial ? " (PARTIAL)" : "");
  if (r.partial) std::printf("note: %s\n", r.note.c_str());
  if (r.first_break_time >= 0)
    std::printf("%ld bonds broken; the first by the frame at t = %g s\n", r.bonds_broken, r.first_break_time);
  else
    std::printf("no bond broke\n");
}

}  // namespace

void add_lammps_command(CLI::App& app) {
  auto o = std::make_shared<LammpsCli>();
  auto* cmd = app.add_subcommand(
      "lammps", "Write a scene as a LAMMPS deck (in.lammps, data, tables) for runs beyond one machine");
  cmd->add_option("scene", o->scene, "Scene file (TOML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Folder for the deck")->required();
  cmd->add_option("--set", o->set, "Override a scene key (repeatable)")->type_name("KEY=VALUE");
  cmd->add_flag("--force", o->force, "Overwrite a deck already in the folder");
  cmd->callback([o] { run(*o); });

  auto im = std::make_shared<ImportCli>();
  auto* imp = app.add_subcommand("import", "Read a LAMMPS run of a `pmfrag lammps` deck into a pmfrag run folder");
  imp->add_option("deck", im->deck, "The deck's folder, after `lmp -in in.lammps` ran there")->required();
  imp->add_option("--out", im->out, "Run folder to write (trajectory.h5, run.json, scene.toml)")->required();
  imp->add_flag("--force", im->force, "Overwrite a trajectory already in the run folder");
  imp->callback([im] { run_import(*im); });
}

}  // namespace pmfrag::app
