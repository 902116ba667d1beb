// A scene: what to simulate, as declared in a TOML file (cases/*.toml). Reading validates everything and
// reports each problem as FILE:LINE: key 'a.b': what is wrong. Only the effects a scene declares exist in it.
#pragma once

#include "pmfrag/body/geometry.hpp"
#include "pmfrag/body/lattice.hpp"
#include "pmfrag/model/material.hpp"

#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace pmfrag {

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class LatticeKind { greenspan_plate, triangular, hcp, fcc };

struct BodySpec {
  std::string name;
  LatticeKind lattice = LatticeKind::triangular;
  double r0 = 0.2;                   ///< cm
  Region shape;                      ///< sites kept (kind all = every generated site)
  std::optional<Vec3> origin;        ///< first site; default: the shape's lower corner
  std::optional<std::array<int, 3>> sites;  ///< sites per direction; default: enough to cover the shape
  std::vector<Region> holes;         ///< sites inside are removed
  std::vector<int> void_sites;       ///< sites removed by their number in the lattice's storage order
  std::vector<Segment> slits;        ///< bonds crossing are removed
  std::string phase;                 ///< phase of its particles (a phase's region may override)
};

struct PhaseSpec {
  std::string name;
  // Either derived by the material model (Sec. 5.1) for (p, q), r0 and a block, or given directly.
  bool derived = true;
  int p = 7, q = 14;
  Block block;
  double G = 0.0, H = 0.0, mass = 0.0;  ///< when not derived (dyne cm^p, dyne cm^q, g)
  std::optional<Region> region;          ///< particles inside take this phase (inclusions)
};

struct InterfaceSpec {
  std::string a, b;
  // The law across the interface: the weaker phase law times `scale`, or given by p, q, G, H.
  double scale = 1.0;
  bool explicit_law = false;
  PairLaw law;
};

enum class PairModel { bonded, cutoff };

struct PairSpec {
  PairModel model = PairModel::bonded;
  double cutoff_r0 = 1.7;  ///< D / r0
  double r_min_r0 = 0.0;   ///< force held constant inside r_min (0 = no clamp)
  bool contact = true;     ///< bonded: unbonded particles closer than r0 repel
  /// Arithmetic of the bond sweeps: false = double (default); true = single precision for r², 1/r and the
  /// law (differences of positions and all sums stay double) - the accuracy study's precision knob.
  bool single_precision = false;
};

struct Selection {
  enum class Kind { all, top_row, bottom_row, region, phase, body };
  Kind kind = Kind::all;
  Region region;
  std::string name;  ///< phase or body
  std::string describe() const;
};

struct KinematicSpec {
  Selection select;
  Vec3 velocity = Vec3::Zero();  ///< cm/s
};

struct ImpactorSpec {
  std::string body;
  Vec3 velocity = Vec3::Zero();  ///< cm/s
};

struct DampingSpec {
  double gamma = 0.0;  ///< 1/s: force -gamma m v
};

struct TimeSpec {
  bool auto_dt = false;
  bool adaptive = false;  ///< dt = "adaptive": each step safety x Eq. 15 at the closest approach present
  double dt = 1e-7;      ///< s (when neither auto nor adaptive)
  double dt_max = 0.0;   ///< s, adaptive: the cap (0: 0.9 x safety x the stretch limit at r0)
  double safety = 0.5;   ///< auto and adaptive: dt = safety x the Eq. 15 limit
  double end = 0.0;      ///< s
};

struct OutputSpec {
  double every = 1e-4;            ///< s between frames
  double checkpoint_every = 0.0;  ///< s between checkpoints (0: every 10 frames)
  /// Frames' positions and velocities as 64-bit ("double") or 32-bit ("single") floats. Single halves a frame
  /// and rounds each value to 2^-24 of itself (6e-7 cm on a 10 cm body); checkpoints, and so --resume, stay
  /// double.
  bool single_precision = false;
  /// HDF5's deflate (gzip, level 1-9; 0 = none) on frames, after its byte shuffle. Debian's HDF5 has it.
  int gzip_level = 0;
  /// `fields = ["position"]` leaves velocities out of the frames (half a frame): fragment velocities, speed and
  /// kinetic energy per particle are then unknown to the readers. Positions are always written.
  bool velocity = true;
};

struct Scene {
  std::string file;  ///< where it was read from (for messages)
  std::string source;                  ///< the scene text as read
  std::vector<std::string> overrides;  ///< the --set items applied on top of it (kept for --resume)
  /// The text as read with the overrides appended as comments: what a trajectory records.
  std::string recorded_text() const;
  std::string title;
  int dim = 2;
  std::vector<BodySpec> bodies;
  std::vector<PhaseSpec> phases;
  std::vector<InterfaceSpec> interfaces;
  std::optional<PairSpec> pair;
  std::vector<KinematicSpec> kinematic;
  std::vector<ImpactorSpec> impactors;
  std::optional<Vec3> gravity;  ///< cm/s^2
  std::optional<DampingSpec> damping;
  bool greenspan_alpha = false;  ///< Eq. (10) scaling of the pair force (pseudo-dynamic; off unless declared)
  TimeSpec time;
  OutputSpec output;
};

/// Reads and validates a scene. `overrides` are "dotted.key=value" strings (value in TOML syntax; bare words
/// are taken as strings); they replace or add keys before validation.
Scene read_scene(const std::string& path, const std::vector<std::string>& overrides = {});
/// Same, from text (file is only used in messages). If `keys_asked` is given, every key the parser looked for
/// is added to it under its name in docs/scenes.md ("body[].shape" is a "region": "region.kind"; tables in
/// arrays as "kinematic[].select.row").
Scene parse_scene(const std::string& text, const std::string& file, const std::vector<std::string>& overrides = {},
                  std::set<std::string>* keys_asked = nullptr);

}  // namespace pmfrag
