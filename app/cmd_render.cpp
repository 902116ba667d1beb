#include "cmd_render.hpp"

#include "movie.hpp"
#include "parse.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/folder_lock.hpp"
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/analysis/particle_fields.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/render/frames.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace pmfrag::app {

namespace {

struct RenderCli {
  std::string dir, field = "fragment_id", panel, out, cut, camera = "fixed";
  long every = 1;
  int size = 1024;
  double fps = 12.0, vectors = 0.0;
  bool bonds = false;
  bool no_frames = false, movie = false;
};

// What to draw over the particles (--bonds, --vectors).
struct Overlay {
  const std::vector<std::array<int, 2>>* bonds = nullptr;  ///< with their broken flags: --bonds
  const std::vector<std::uint8_t>* broken = nullptr;
  double r0 = 0.2;             ///< cm
  double vector_scale = 0.0;   ///< > 0: displacement vectors, this many times their length
};

// The particles to draw: all, or (cut) those whose initial coordinate on the cut axis is at most the cut
// value, so the same particles show in every frame of a sequence. Overlays join drawn particles only.
render::FramePicture picture(const TrajectoryFrame& f, const std::vector<double>& values, int dim, int cut_axis,
                             double cut_at, const TrajectoryFrame& first, const Overlay& overlay) {
  render::FramePicture p;
  const std::size_t n = values.size(), d = static_cast<std::size_t>(dim);
  std::vector<std::uint8_t> drawn(n, 0);
  p.xyz.reserve(3 * n), p.value.reserve(n);
  auto at = [&](const std::vector<double>& x, std::size_t i, std::size_t c) { return c < d ? x[i * d + c] : 0.0; };
  for (std::size_t i = 0; i < n; ++i) {
    if (cut_axis >= 0 && first.position[i * d + static_cast<std::size_t>(cut_axis)] > cut_at) continue;
    drawn[i] = 1;
    for (std::size_t c = 0; c < 3; ++c) p.xyz.push_back(at(f.position, i, c));
    p.value.push_back(values[i]);
  }
  if (overlay.bonds) {
    // Intact bonds in grey; a broken bond in red while its ends are within 3 r0 (the faces of a crack that has
    // just opened), not across the gap between fragments that have flown apart.
    for (std::size_t b = 0; b < overlay.bonds->size(); ++b) {
      const auto i = static_cast<std::size_t>((*overlay.bonds)[b][0]), j = static_cast<std::size_t>((*overlay.bonds)[b][1]);
      if (!drawn[i] || !drawn[j]) continue;
      double r2 = 0;
      for (std::size_t c = 0; c < d; ++c) r2 += std::pow(f.position[i * d + c] - f.position[j * d + c], 2);
      const bool broken = (*overlay.broken)[b] != 0;
      if (broken && r2 > 9.0 * overlay.r0 * overlay.r0) continue;
      for (std::size_t c = 0; c < 3; ++c) p.segments.push_back(at(f.position, i, c));
      for (std::size_t c = 0; c < 3; ++c) p.segments.push_back(at(f.position, j, c));
      p.segment_kinds.push_back(broken ? render::SegmentKind::broken_bond : render::SegmentKind::intact_bond);
    }
  }
  if (overlay.vector_scale > 0) {
    for (std::size_t i = 0; i < n; ++i) {
      if (!drawn[i]) continue;
      for (std::size_t c = 0; c < 3; ++c) p.segments.push_back(at(f.position, i, c));
      for (std::size_t c = 0; c < 3; ++c)
        p.segments.push_back(at(f.position, i, c) + overlay.vector_scale * (at(f.position, i, c) - at(first.position, i, c)));
      p.segment_kinds.push_back(render::SegmentKind::vector);
    }
  }
  p.time = f.time;
  return p;
}

// Every frame allocates and frees buffers the size of the frame (VTK's image grab, the PNG, llvmpipe's).
// glibc gives each back to the kernel and the next frame faults it in again: a third of the plate's render
// time went to page faults (perf). Keeping freed memory in the heap doubles the plate's frame rate.
void keep_freed_frame_buffers() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

void run(const RenderCli& o) {
  keep_freed_frame_buffers();
  const std::vector<std::string> fields{"fragment_id", "displacement", "damage", "speed", "phase"};
  if (std::find(fields.begin(), fields.end(), o.field) == fields.end())
    throw UsageError("--field: expected fragment_id, displacement, damage, speed or phase (got '" + o.field + "')");
  if (o.size < 64 || o.size > 8192) throw UsageError("--size: must be in 64..8192");
  if (o.vectors < 0) throw UsageError("--vectors: the scale must be positive");
  if (o.movie && o.no_frames) throw UsageError("--movie is made of the frames: it cannot go with --no-frames");
  namespace fs = std::filesystem;
  const fs::path dir(o.dir);
  if (!fs::exists(dir / "trajectory.h5")) throw UsageError(o.dir + ": no trajectory.h5 (run `pmfrag run` first)");
  const FolderLock lock(o.dir);  // one writer per run folder: a second is refused at once
  std::vector<double> panel_at;
  if (!o.panel.empty()) {
    std::stringstream ss(o.panel);
    for (std::string s; std::getline(ss, s, ',');) {
      const auto v = parse_numbers("--panel", s, 1)[0];
      if (v < 0 || v > 1) throw UsageError("--panel: each value is a fraction of the run's duration in [0, 1]");
      panel_at.push_back(v);
    }
  }

  H5mdReader rd((dir / "trajectory.h5").string());
  if (o.field == "speed" && !rd.has_velocity())
    throw UsageError("--field speed: " + o.dir + " holds no velocities (its scene's output.fields left them out)");
  const int dim = rd.dim();
  // --cut AXIS=VALUE keeps the particles on the near side of a plane (3-D: the interior shows on the cut).
  int cut_axis = -1;
  double cut_at = 0.0;
  if (!o.cut.empty()) {
    const auto eq = o.cut.find('=');
    const std::string axis = o.cut.substr(0, eq);
    if (eq == std::string::npos || (axis != "x" && axis != "y" && axis != "z") || (axis == "z" && dim == 2))
      throw UsageError("--cut: expected x=VALUE, y=VALUE or (3-D) z=VALUE in cm (got '" + o.cut + "')");
    cut_axis = axis[0] - 'x';
    cut_at = parse_numbers("--cut", o.cut.substr(eq + 1), 1)[0];
  }
  const auto species = rd.species();
  const auto mass = rd.mass();
  const double r0 = rd.parameter("r0");
  // Broken bonds as the engine recorded them (older trajectories: longer than D at a frame).
  analysis::BondStates states = analysis::BondStates::open(rd, std::nullopt);
  const analysis::FragmentTracker tracker(rd.particles(), rd.bonds(), mass);
  // Only the leading frames that read back whole (a cut file, a frame failing its checksum): the sequence is
  // then marked partial, on the terminal and in frames/PARTIAL.txt.
  long frames = rd.frames();
  TrajectoryFrame f;  // one buffer for every pass over the frames: millions of particles are not reallocated per frame
  std::string damage = analysis::trajectory_caveats(rd);  // a damaged file, a run short of its end
  for (long k = 0; k < frames; ++k) {
    if (!states.covers(k)) {
      analysis::add_note(damage, states.damage());
      frames = k;
      break;
    }
    try {
      rd.frame(k, f);
    } catch (const std::exception& e) {
      analysis::add_note(damage, "frame " + std::to_string(k) + " unreadable (" + e.what() + ")");
      frames = k;
    }
  }
  if (frames == 0) throw std::runtime_error((dir / "trajectory.h5").string() + ": no readable frame (" + damage + ")");
  if (!damage.empty())
    std::fprintf(stderr, "pmfrag: warning: %s: rendering frames 0..%ld only (PARTIAL)\n",
                 damage.c_str(), frames - 1);
  const std::vector<double> times = rd.times();
  const TrajectoryFrame first = rd.frame(0);

  // --camera fixed frames the first frame's body for the whole sequence (a crack grows in a still picture);
  // follow frames each frame's particles, so bodies that move (an impactor, fragments in flight) stay in view.
  const bool follow = o.camera == "follow";
  render::View view = render::view_of(first.position, dim, r0);
  render::View panel_view = view;

  const std::vector<std::uint8_t> target = analysis::target_particles(rd);
  const bool any_target = std::find(target.begin(), target.end(), 1) != target.end();
  render::FieldSpec spec;
  spec.categorical = o.field == "fragment_id" || o.field == "phase";
  spec.title = o.field == "fragment_id"    ? (any_target ? "fragment\n(pale: held)" : "fragment")
               : o.field == "phase"        ? "phase"
               : o.field == "damage"       ? "damage"
               : o.field == "displacement" ? "displacement\n[cm]"
                                           : "speed\n[cm/s]";
  if (!spec.categorical) {  // one range for the whole sequence, from a pre-pass
    spec.min = 0.0;
    spec.max = o.field == "damage" ? 1.0 : 0.0;
    if (o.field != "damage") {
      analysis::BondStates probe = analysis::BondStates::open(rd, std::nullopt);
      for (long k = 0; k < frames; ++k) {
        rd.frame(k, f);
        probe.advance(k, f.position);
        const auto labels = tracker.label(probe.broken());
        const auto v = analysis::particle_field(o.field, {f, first, labels, species, mass, dim});
        spec.max = std::max(spec.max, *std::max_element(v.begin(), v.end()));
      }
    }
  }
  const std::string title = analysis::run_title(rd, o.dir);

  render::HeadlessWindow window(o.size, o.size);
  const fs::path frames_dir = dir / "frames";
  // The sequence is drawn into frames.part/ and takes the place of frames/ once every frame is on disk: a render
  // that fails or is killed leaves the previous frames as they were, and an earlier render's frames (another
  // --every) never mix into the movie.
  const fs::path staged_dir = dir / "frames.part";
  if (!o.no_frames) {
    require_folder_or_nothing(frames_dir);
    fs::remove_all(staged_dir);  // what a killed render left
    make_folder(staged_dir);
    if (!damage.empty())
      write_file_atomically(staged_dir / "PARTIAL.txt", [&](std::ostream& note) {
        note << "frames 0.." << frames - 1 << " of a damaged trajectory: " << damage << "\n";
      });
  }
  std::vector<long> panel_frames;
  for (double a : panel_at) {
    const double t = a * times[static_cast<std::size_t>(frames - 1)];
    long best = 0;
    for (long k = 0; k < frames; ++k)
      if (std::fabs(times[static_cast<std::size_t>(k)] - t) < std::fabs(times[static_cast<std::size_t>(best)] - t)) best = k;
    panel_frames.push_back(best);
  }
  std::vector<render::FramePicture> panel(panel_frames.size());
  const auto bond_list = rd.bonds();
  Overlay overlay;
  if (o.bonds) overlay.bonds = &bond_list, overlay.broken = &states.broken();
  overlay.r0 = r0;
  overlay.vector_scale = o.vectors;
  const auto t0 = std::chrono::steady_clock::now();
  long rendered = 0;
  // A render that fails takes its unfinished frames with it (declared before the queue, so that it runs after
  // the queue's thread has stopped writing).
  struct RemoveUnlessDone {
    fs::path dir;
    bool done = false;
    ~RemoveUnlessDone() {
      std::error_code ec;
      if (!done && !dir.empty()) fs::remove_all(dir, ec);
    }
  } unfinished{o.no_frames ? fs::path() : staged_dir};
  const auto frames_not_written = [&](const std::runtime_error& e) {
    return std::runtime_error(frames_dir.string() + ": the new frames were not written, the previous ones are kept: " +
                              e.what());
  };
  render::PngQueue png_queue;  // frames are encoded while the next one renders
  for (long k = 0; k < frames; ++k) {
    rd.frame(k, f);
    states.advance(k, f.position);  // every frame: the distance reading is history-dependent
    const auto lab = tracker.label(states.broken());
    const bool want_frame = !o.no_frames && (k % o.every == 0 || k == frames - 1);
    const bool in_panel = std::find(panel_frames.begin(), panel_frames.end(), k) != panel_frames.end();
    if (!want_frame && !in_panel) continue;
    auto values = analysis::particle_field(o.field, {f, first, lab, species, mass, dim});
    if (o.field == "fragment_id")  // targets held in place are not fragments: drawn pale grey (the colour of NaN)
      for (std::size_t i = 0; i < values.size(); ++i)
        if (target[i]) values[i] = std::numeric_limits<double>::quiet_NaN();
    auto pic = picture(f, values, dim, cut_axis, cut_at, first, overlay);
    if (follow) {
      view = render::view_of(f.position, dim, r0);
      if (in_panel) panel_view = render::enclose(panel_view, view);
    }
    if (want_frame) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%05ld.png", k);
      try {
        render::render_png(window, view, spec, {pic}, "", o.size, o.size, (staged_dir / name).string(), 1, &png_queue);
      } catch (const std::runtime_error& e) {
        throw frames_not_written(e);
      }
      ++rendered;
    }
    for (std::size_t j = 0; j < panel_frames.size(); ++j)
      if (panel_frames[j] == k) panel[j] = pic;
  }
  try {
    png_queue.finish();
  } catch (const std::runtime_error& e) {
    throw frames_not_written(e);
  }
  if (!o.no_frames) replace_directory(frames_dir, staged_dir);
  unfinished.done = true;
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.no_frames)
    std::printf("rendered %ld frames to %s (%.1f frames/s incl. PNG)\n", rendered, frames_dir.c_str(), rendered / secs);
  if (o.movie) {
    encode_movie(frames_dir, dir, o.fps);
    std::printf("wrote the movie %s and %s (%g frames/s)\n", (dir / "crack.mp4").c_str(), (dir / "crack.gif").c_str(),
                o.fps);
  }
  if (!panel.empty()) {
    const char* letters = "abcdefghijklmnopqrstuvwxyz";
    for (std::size_t j = 0; j < panel.size(); ++j) panel[j].caption = std::string("(") + letters[j % 26] + ")";
    const std::string out = o.out.empty() ? (dir / "panel.png").string() : o.out;
    const int w = o.size / 2;
    const double aspect = (panel_view.ymax - panel_view.ymin) / std::max(1e-9, panel_view.xmax - panel_view.xmin);
    const int h = static_cast<int>(w * std::clamp(aspect, 0.5, 2.0));
    render::render_png(window, panel_view, spec, panel, title, w, h, out, 9);
    std::printf("wrote the %zu-panel figure %s\n", panel.size(), out.c_str());
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderCli>();
  auto* cmd = app.add_subcommand("render", "PNG frames of a run (RUN_DIR/frames/) and figure panels, with no display");
  cmd->add_option("run_dir", o->dir, "Run folder (holds trajectory.h5)")->required();
  cmd->add_option("--field", o->field, "Colour by: fragment_id (default), displacement, damage, speed, phase");
  cmd->add_option("--every", o->every, "Render every K-th frame (the last always)")->check(CLI::PositiveNumber);
  cmd->add_option("--size", o->size, "Frame size in pixels (square, default 1024)");
  cmd->add_option("--panel", o->panel,
                  "Also compose one figure of these times, as fractions of the run, e.g. 0,0.7,0.9,1 (like Figs. 4-6)")
      ->type_name("F1,F2,...");
  cmd->add_option("--panel-out", o->out, "Where to write the panel (default RUN_DIR/panel.png)");
  cmd->add_flag("--no-frames", o->no_frames, "Only the panel, no frame sequence");
  cmd->add_flag("--bonds", o->bonds, "Draw bonds: intact grey, just-broken red (ends within 3 r0)");
  cmd->add_option("--vectors", o->vectors, "Draw displacement vectors, this many times their length (e.g. 5)")
      ->type_name("SCALE");
  cmd->add_flag("--movie", o->movie, "Also encode the frames as RUN_DIR/crack.mp4 and crack.gif (needs ffmpeg)");
  cmd->add_option("--fps", o->fps, "Movie frame rate (default 12)")->check(CLI::Range(0.1, 120.0));
  cmd->add_option("--camera", o->camera,
                  "fixed (default): framed on the first frame's body, the same for every frame; follow: framed on "
                  "each frame's particles, so moving bodies stay in view (a panel then frames all of its times)")
      ->check(CLI::IsMember({"fixed", "follow"}));
  cmd->add_option("--cut", o->cut, "Show only particles with initial x, y or z at most VALUE cm, e.g. --cut z=1.5 "
                                   "(3-D: look inside the block)");
  cmd->callback([o] { run(*o); });
}

}  // namespace pmfrag::app
