// Pictures of particle frames: particles as shaded discs coloured by a field, a colour bar with units, a time
// label and a 1 cm scale bar, under a camera fixed to the initial body. One frame per image, or several side
// by side as a figure panel (the paper's Figs. 4-6).
#pragma once

#include "pmfrag/render/headless.hpp"
#include "pmfrag/render/png_queue.hpp"

#include <string>
#include <vector>

namespace pmfrag::render {

struct FieldSpec {
  std::string title;         ///< colour bar title with units, e.g. "displacement [cm]"
  bool categorical = false;  ///< fragment ids, phases: a cycling colour-blind-safe palette
  double min = 0.0, max = 1.0;
};

/// What a camera frames: the initial body's bounding box, fixed over a sequence.
struct View {
  double xmin = 0, xmax = 1, ymin = 0, ymax = 1;
  double radius = 0.09;  ///< particle disc radius [cm]
  /// 3-D: a perspective camera looking obliquely at the box [xmin..xmax] x [ymin..ymax] x [zmin..zmax]
  /// (2-D: orthographic, looking down z).
  bool three_d = false;
  double zmin = 0, zmax = 0;
};

/// The box around a frame's particles (`dim` coordinates each [cm]), drawn with discs of 0.45 r0: a sequence
/// is framed on its first frame's, or on each frame's (`pmfrag render --camera follow`).
View view_of(const std::vector<double>& position, int dim, double r0);
/// The smallest view holding both boxes (a panel of frames under a camera that follows).
View enclose(const View& a, const View& b);

/// Where the camera of a panel stands, the same for every frame of a sequence: what render_png uses, and what
/// `pmfrag export --paraview-script` hands to ParaView. `aspect` is the panel's width over its height.
struct CameraPose {
  double position[3], focal_point[3], view_up[3];  ///< cm
  bool parallel = false;        ///< 2-D: orthographic, looking down z
  double parallel_scale = 1.0;  ///< half the panel's height [cm] (parallel only)
  double view_angle_deg = 30.0;  ///< vertical (perspective only)
  double near = 0.1, far = 200.0;  ///< clipping range [cm]
};
CameraPose camera_pose(const View& view, double aspect);
/// A particle's radius in pixels at the camera's focal point, in a panel of this size (the choice of
/// supersampling depends on it).
double splat_radius_pixels(const View& view, int panel_w, int panel_h);

/// What a line overlay is: an intact bond (dark grey), a broken bond (red), a displacement vector (black).
enum class SegmentKind : unsigned char { intact_bond, broken_bond, vector };

struct FramePicture {
  std::vector<double> xyz;    ///< 3 per particle [cm]
  std::vector<double> value;  ///< one per particle (field value, or category index)
  std::vector<double> segments;             ///< optional lines drawn over the particles: 6 per segment [cm]
  std::vector<SegmentKind> segment_kinds;   ///< one per segment
  double time = 0.0;          ///< s
  std::string caption;        ///< under the time in panels, e.g. "(b)"
};

/// Renders pictures side by side (one or more) into a PNG of panel_w*count x panel_h (+ a title strip when
/// title is not empty). Throws std::runtime_error if the PNG cannot be written. With a queue the PNG is
/// encoded on the queue's thread (errors surface from a later push or PngQueue::finish()).
void render_png(HeadlessWindow& window, const View& view, const FieldSpec& field,
                const std::vector<FramePicture>& pictures, const std::string& title, int panel_w, int panel_h,
                const std::string& png_path, int png_compression = 4, PngQueue* queue = nullptr);

}  // namespace pmfrag::render
