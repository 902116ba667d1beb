#include "cmd_export.hpp"

#include "parse.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/analysis/export_mdanalysis.hpp"
#include "pmfrag/analysis/export_vtk.hpp"
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/render/paraview_script.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace pmfrag::app {

namespace {

struct ExportCli {
  std::string dir, fields, criterion, compress = "lz4", format = "vtk";
  long every = 1;
  bool paraview_script = false;
  CLI::Option *fields_opt = nullptr, *break_opt = nullptr, *compress_opt = nullptr, *script_opt = nullptr;
};

// --format mdanalysis: the frames alone, in MDAnalysis' units (export_mdanalysis.hpp).
void run_mdanalysis(const ExportCli& o) {
  for (const CLI::Option* opt : {o.fields_opt, o.break_opt, o.compress_opt, o.script_opt})
    if (opt->count() > 0) throw UsageError(opt->get_name() + " applies to --format vtk only");
  if (!std::filesystem::exists(std::filesystem::path(o.dir) / "trajectory.h5"))
    throw UsageError(o.dir + ": no trajectory.h5 (run `pmfrag run SCENE --out DIR` first)");
  const FolderLock lock(o.dir);  // one writer per run folder
  remove_temporaries(std::filesystem::path(o.dir) / "mdanalysis");
  analysis::MdanalysisExportOptions opt;
  opt.every = o.every;
  const auto r = analysis::export_mdanalysis(o.dir, opt);
  std::printf("exported %ld frames to %s (MDAnalysis: positions in Angstrom, velocities in Angstrom/ps, time in s)%s\n",
              r.frames_written, r.path.c_str(), r.partial ? " (PARTIAL)" : "");
  if (r.partial) std::printf("note: %s\n", r.note.c_str());
}

void run(const ExportCli& o) {
  if (o.format == "mdanalysis") return run_mdanalysis(o);
  analysis::ExportOptions opt;
  opt.every = o.every;
  opt.compression = o.compress == "zlib" ? analysis::Compression::zlib
                    : o.compress == "none" ? analysis::Compression::none
                                           : analysis::Compression::lz4;
  try {
    opt.criterion = analysis::BreakCriterion::parse_option(o.criterion);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  std::stringstream ss(o.fields);
  for (std::string f; std::getline(ss, f, ',');)
    if (!f.empty()) {
      if (!analysis::export_fields().count(f)) throw UsageError("--fields: unknown field '" + f + "'");
      opt.fields.insert(f);
    }
  if (!std::filesystem::exists(std::filesystem::path(o.dir) / "trajectory.h5"))
    throw UsageError(o.dir + ": no trajectory.h5 (run `pmfrag run SCENE --out DIR` first)");
  const FolderLock lock(o.dir);  // one writer per run folder: a second is refused at once
  remove_temporaries(std::filesystem::path(o.dir) / "vtk");  // a killed export's half-written frame
  const auto r = analysis::export_vtk(o.dir, opt);
  std::printf("exported %ld of %ld frames to %s/vtk/ and %s/particles.pvd%s\n", r.frames_written, r.frames_read,
              o.dir.c_str(), o.dir.c_str(), r.partial ? " (PARTIAL)" : "");
  if (r.partial) std::printf("note: %s\n", r.note.c_str());
  if (o.paraview_script) {
    if (opt.fields.size() > 0 && !opt.fields.count("fragment_id"))
      throw UsageError("--paraview-script colours by fragment_id: add it to --fields");
    const H5mdReader rd((std::filesystem::path(o.dir) / "trajectory.h5").string());
    const render::View view = render::view_of(rd.frame(0).position, rd.dim(), rd.parameter("r0"));
    const std::filesystem::path script = std::filesystem::path(o.dir) / "particles_view.py";
    write_file_atomically(script, render::paraview_script(view, analysis::run_title(rd, o.dir), 1024));
    std::printf("wrote %s (paraview --script=%s, or pvpython %s --screenshot view.png)\n", script.c_str(),
                script.c_str(), script.c_str());
  }
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto o = std::make_shared<ExportCli>();
  auto* cmd = app.add_subcommand("export", "Write VTU frames and a PVD collection for ParaView, or an H5MD copy for MDAnalysis");
  cmd->add_option("run_dir", o->dir, "Run folder (holds trajectory.h5)")->required();
  cmd->add_option("--format", o->format,
                  "vtk (default): RUN/vtk/*.vtu and RUN/particles.pvd; mdanalysis: RUN/mdanalysis/trajectory.h5md, "
                  "which mda.Universe() opens as it is (Angstrom = 1e-8 cm, Angstrom/ps, s; z = 0 in 2-D)")
      ->check(CLI::IsMember({"vtk", "mdanalysis"}));
  cmd->add_option("--every", o->every, "Write every K-th frame (the last always)")->check(CLI::PositiveNumber);
  std::string names;
  for (const auto& f : analysis::export_fields()) names += (names.empty() ? "" : ", ") + f;
  o->fields_opt = cmd->add_option("--fields", o->fields, "Comma-separated arrays to write (default all): " + names)->type_name("A,B,...");
  o->break_opt = cmd->add_option("--break", o->criterion,
                  "Read broken bonds from their lengths at the frames: longer than D, rd, or a factor of r0 (default: "
                  "the engine's record of the bonds it broke)")
      ->type_name("D|rd|FACTOR");
  o->compress_opt = cmd->add_option("--compress", o->compress,
                  "Compression of the VTU data: lz4 (default, fastest to write), zlib (about 25 % smaller), none")
      ->check(CLI::IsMember({"lz4", "zlib", "none"}));
  o->script_opt = cmd->add_flag("--paraview-script", o->paraview_script,
                  "Also write RUN/particles_view.py: ParaView opens particles.pvd coloured by fragment_id under the "
                  "camera of pmfrag's frames (paraview --script=..., or pvpython ... --screenshot PNG)");
  cmd->callback([o] { run(*o); });
}

}  // namespace pmfrag::app
