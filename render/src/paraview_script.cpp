#include "pmfrag/render/paraview_script.hpp"

#include "ramp.hpp"

#include <charconv>
#include <string>

namespace pmfrag::render {

namespace {

// The shortest text that reads back as the same double.
std::string number(double v) {
  char buf[32];
  const auto end = std::to_chars(buf, buf + sizeof buf, v).ptr;
  return std::string(buf, end);
}

std::string triple(const double v[3]) {
  std::string out = "(";  // appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "(" + std::string
  for (int a = 0; a < 3; ++a) out.append(number(v[a])).append(a < 2 ? ", " : ")");
  return out;
}

// A Python string literal: the title comes from the scene file and --set, so quotes and backslashes are escaped.
std::string python_string(const std::string& s) {
  std::string out(1, '"');
  for (const char c : s) {
    if (c == '\\' || c == '"') {
      out.push_back('\\');
      out.push_back(c);
    } else if (c == '\n') {
      out.append("\\n");
    } else {
      out.push_back(static_cast<unsigned char>(c) < 0x20 ? ' ' : c);
    }
  }
  out.push_back('"');
  return out;
}

}  // namespace

std::string paraview_script(const View& view, const std::string& title, int size_px) {
  const CameraPose pose = camera_pose(view, 1.0);  // the frames are square
  std::string palette;
  for (const auto& c : detail::category_palette)
    palette += "    " + number(c[0]) + ", " + number(c[1]) + ", " + number(c[2]) + ",\n";
  const auto& grey = detail::no_category;

  std::string s;
  s += R"py(# The pmfrag run in this folder as its frames show it: particles.pvd as shaded spheres coloured by
# fragment_id with pmfrag's palette, under the camera of `pmfrag render`. Written by
# `pmfrag export RUN --paraview-script`; the collection is found beside this file, so the folder can move.
#
#   ParaView:  paraview --script=RUN/particles_view.py    (or View > Python Shell > Run Script)
#   headless:  pvpython RUN/particles_view.py --screenshot view.png [--time T] [--size PX] [--no-legend]
#
# Without --time the last frame is shown. Positions are in cm, times in s.
import os
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction, GetScalarBar,
                             PVDReader, Render, SaveScreenshot, Show, Text)

HERE = os.path.dirname(os.path.abspath(__file__))
COLLECTION = os.path.join(HERE, "particles.pvd")
TITLE = )py" + python_string(title) + R"py(
RADIUS_CM = )py" + number(view.radius) + R"py(  # 0.45 r0, as in pmfrag's frames
SIZE_PX = )py" + std::to_string(size_px) + R"py(  # the frames' side; the camera is framed for a square view
CAMERA = {
    "position": )py" + triple(pose.position) + R"py(,
    "focal_point": )py" + triple(pose.focal_point) + R"py(,
    "view_up": )py" + triple(pose.view_up) + R"py(,
    "parallel": )py" + (pose.parallel ? "True" : "False") + R"py(,
    "parallel_scale": )py" + number(pose.parallel_scale) + R"py(,
    "view_angle": )py" + number(pose.view_angle_deg) + R"py(,
}
# Fragment k takes colour k mod 8 (Okabe-Ito); 0 is the largest fragment. Fragments past CATEGORIES, the
# smallest ones, and particles in no fragment (targets held in place) are grey. The legend is shown for up to
# 24 fragments.
PALETTE = [
)py" + palette + R"py(]
GREY = [)py" + number(grey[0]) + ", " + number(grey[1]) + ", " + number(grey[2]) + R"py(]
CATEGORIES = 256


def frame_times(reader):
    """The collection's times [s]: ParaView gives a property holding several, or a number for one."""
    values = reader.TimestepValues
    try:
        return [float(t) for t in values]
    except TypeError:
        return [float(values)]


def show_run(view=None, legend=True):
    """Opens the collection in `view` (default: the active render view); returns (reader, display, view)."""
    reader = PVDReader(registrationName="pmfrag particles", FileName=COLLECTION)
    view = view or GetActiveViewOrCreate("RenderView")
    display = Show(reader, view)
    display.SetRepresentationType("Point Gaussian")
    display.ShaderPreset = "Sphere"
    display.GaussianRadius = RADIUS_CM
    ColorBy(display, ("POINTS", "fragment_id"))
    lut = GetColorTransferFunction("fragment_id")
    lut.InterpretValuesAsCategories = 1
    # As many categories as the last frame has fragments (up to CATEGORIES); a legend only while it stays short.
    reader.UpdatePipeline(frame_times(reader)[-1])
    count = min(CATEGORIES, int(reader.PointData["fragment_id"].GetRange()[1]) + 1)
    annotations, colours = [], []
    for k in range(count):
        annotations += [str(k), str(k)]
        colours += PALETTE[3 * (k % 8):3 * (k % 8) + 3]
    lut.Annotations = annotations
    lut.IndexedColors = colours
    lut.NanColor = GREY
    show_legend = legend and count <= 24
    display.SetScalarBarVisibility(view, show_legend)
    if show_legend:
        # ParaView's default legend text is white (for its dark background): dark here, and the numbers to
        # the right of the bar, clear of the body.
        bar = GetScalarBar(lut, view)
        bar.Title, bar.ComponentTitle = "fragment\n(0: largest)", ""
        bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
        bar.TextPosition = "Ticks left/bottom, annotations right/top"
        bar.WindowLocation = "Any Location"
        bar.Position = [0.85, 0.06]
        bar.HorizontalTitle = 1
        bar.TitleFontSize = bar.LabelFontSize = 11
        bar.ScalarBarThickness = 12
        bar.ScalarBarLength = 0.4
    if TITLE and legend:
        label = Text(registrationName="pmfrag title", Text=TITLE)
        shown = Show(label, view)
        shown.WindowLocation = "Upper Left Corner"
        shown.Color = [0.1, 0.1, 0.1]
        shown.FontSize = 14
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.OrientationAxesVisibility = 0
    Render(view)  # ParaView frames the data on a view's first render; the frames' camera is set after it
    view.CameraPosition = list(CAMERA["position"])
    view.CameraFocalPoint = list(CAMERA["focal_point"])
    view.CameraViewUp = list(CAMERA["view_up"])
    view.CameraParallelProjection = 1 if CAMERA["parallel"] else 0
    view.CameraParallelScale = CAMERA["parallel_scale"]
    view.CameraViewAngle = CAMERA["view_angle"]
    GetAnimationScene().UpdateAnimationUsingDataTimeSteps()
    return reader, display, view


def main(argv):
    options = {"--screenshot": None, "--time": None, "--size": str(SIZE_PX)}
    legend = True
    args = list(argv)
    while args:
        key = args.pop(0)
        if key == "--no-legend":
            legend = False
        elif key in options and args:
            options[key] = args.pop(0)
        else:
            sys.exit("particles_view.py: unknown or incomplete option " + repr(key) +
                     " (expected --screenshot PNG, --time T, --size PX, --no-legend)")
    reader, display, view = show_run(legend=legend)
    times = frame_times(reader)
    t = float(options["--time"]) if options["--time"] is not None else times[-1]
    GetAnimationScene().AnimationTime = t
    view.ViewTime = t
    if options["--screenshot"]:
        side = int(options["--size"])
        SaveScreenshot(options["--screenshot"], view, ImageResolution=[side, side])
        print("particles_view.py: wrote " + options["--screenshot"] + " (t = %g s, %d x %d)" % (t, side, side))
    else:
        Render(view)


if __name__ == "__main__":
    main([a for a in sys.argv[1:] if a])
)py";
  return s;
}

}  // namespace pmfrag::render
