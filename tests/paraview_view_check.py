"""`pmfrag export --paraview-script`'s RUN/particles_view.py under ParaView's own pvpython: the screenshot shows
the body where the frames' camera puts it, coloured as fragment 0 (scripts/paraview-check runs it).
    pvpython --force-offscreen-rendering tests/paraview_view_check.py RUN_DIR
"""
import sys
from pathlib import Path

from paraview import servermanager
from paraview.simple import OpenDataFile, UpdatePipeline

run = Path(sys.argv[1])


def fail(msg):
    print(f"paraview_view_check: FAIL: {msg}")
    sys.exit(1)


reader = OpenDataFile(str(run / "particles.pvd"))
times_pv = list(reader.TimestepValues)

# `pmfrag export --paraview-script`: the script opens the collection coloured by fragment_id under the frames'
# camera. Run it as a user would (its own main), screenshot the first frame without legend or title, and find the
# body where that camera puts it: in a parallel view of half-height S about the focal point F, a point x lands at
# pixel W/2 + (x - F) / (2 S) * W.
script = run / "particles_view.py"
if not script.exists():
    fail(f"{script} not found (pmfrag export RUN --paraview-script)")
import runpy
import tempfile

side = 512
shot = Path(tempfile.mkdtemp()) / "view.png"
saved_argv = sys.argv
sys.argv = [str(script), "--screenshot", str(shot), "--time", repr(times_pv[0]), "--size", str(side), "--no-legend"]
view_module = runpy.run_path(str(script), run_name="__main__")
sys.argv = saved_argv
camera = view_module["CAMERA"]
radius = view_module["RADIUS_CM"]
if not shot.exists():
    fail(f"{script} wrote no screenshot")

from paraview.simple import GetActiveView, GetColorTransferFunction
view = GetActiveView()
if not view.CameraParallelProjection or abs(view.CameraParallelScale - camera["parallel_scale"]) > 1e-9:
    fail(f"ParaView's camera is not the script's: parallel {view.CameraParallelProjection}, scale {view.CameraParallelScale}")
lut = GetColorTransferFunction("fragment_id")
if not lut.InterpretValuesAsCategories:
    fail("fragment_id is not coloured as categories")

from vtkmodules.vtkIOImage import vtkPNGReader
png = vtkPNGReader()
png.SetFileName(str(shot))
png.Update()
image = png.GetOutput()
w, h, _ = image.GetDimensions()
if (w, h) != (side, side):
    fail(f"the screenshot is {w} x {h}, asked for {side} x {side}")
pixels = image.GetPointData().GetScalars()
cols, rows, red, green, blue = [], [], 0.0, 0.0, 0.0
for j in range(h):
    for i in range(w):
        rgb = [pixels.GetComponent(j * w + i, c) for c in range(3)]
        if min(rgb) < 235:  # not the white background
            cols.append(i)
            rows.append(j)
            red, green, blue = red + rgb[0], green + rgb[1], blue + rgb[2]
if not cols:
    fail("the screenshot is blank")
UpdatePipeline(time=times_pv[0], proxy=reader)
x0, x1, y0, y1, _, _ = servermanager.Fetch(reader).GetBounds()
scale, (fx, fy, _) = camera["parallel_scale"], camera["focal_point"]
pixel = lambda x, f: side / 2 + (x - f) / (2 * scale) * side
want_x = (pixel(x0 - radius, fx), pixel(x1 + radius, fx))
want_y = (pixel(y0 - radius, fy), pixel(y1 + radius, fy))
got_x, got_y = (min(cols), max(cols) + 1), (min(rows), max(rows) + 1)  # vtkPNGReader: row 0 at the bottom
tol = 4.0
for got, want, axis in ((got_x, want_x, "x"), (got_y, want_y, "y")):
    if abs(got[0] - want[0]) > tol or abs(got[1] - want[1]) > tol:
        fail(f"the body spans pixels {got} in {axis}; the frames' camera puts it at ({want[0]:.1f}, {want[1]:.1f})")
n = len(cols)
if not red / n > green / n > blue / n:  # fragment 0 takes pmfrag's first colour, orange (0.90, 0.62, 0.00)
    fail(f"the body's mean colour {red / n:.0f}, {green / n:.0f}, {blue / n:.0f} is not pmfrag's orange for fragment 0")
print(f"paraview_view_check: particles_view.py: body at pixels x {got_x}, y {got_y} of {side}^2 where the frames' camera"
      f" puts it ({want_x[0]:.1f}..{want_x[1]:.1f}, {want_y[0]:.1f}..{want_y[1]:.1f}); mean colour"
      f" {red / n:.0f}, {green / n:.0f}, {blue / n:.0f} (orange: fragment 0)")
print("paraview_view_check: OK (particles_view.py shows the run under the frames' camera, coloured by fragment_id)")
