"""ParaView's own reader opens a pmfrag run's particles.pvd (issue 4's acceptance check).

Run with Debian's pvpython (package python3-paraview), never with pmfrag's own VTK:
    pvpython tests/paraview_check.py RUN_DIR
It loads the collection with ParaView's PVD reader, steps through every time, fetches each frame to the
client and reads `fragment_id`; it checks the times against the collection file, the particle count against
the trajectory's, and the fragment count of every frame against pmfrag's own fragments_timeline.csv.
Prints one line per check and exits non-zero on the first mismatch.
"""
import csv
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from paraview import servermanager
from paraview.simple import OpenDataFile, UpdatePipeline

run = Path(sys.argv[1])
pvd = run / "particles.pvd"


def fail(msg):
    print(f"paraview_check: FAIL: {msg}")
    sys.exit(1)


# What the collection says, read as plain XML (independent of any VTK code).
datasets = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
times_xml = [float(d.get("timestep")) for d in datasets]
if not times_xml:
    fail(f"{pvd} lists no frames")

reader = OpenDataFile(str(pvd))
if reader is None:
    fail(f"ParaView found no reader for {pvd}")
print(f"paraview_check: {reader.GetXMLName()} opened {pvd}")
times_pv = list(reader.TimestepValues)
if len(times_pv) != len(times_xml):
    fail(f"ParaView sees {len(times_pv)} times, the .pvd lists {len(times_xml)}")
for a, b in zip(times_pv, times_xml):
    if abs(a - b) > 1e-12 * max(1.0, abs(b)):
        fail(f"time {a} read by ParaView != {b} in the .pvd")
print(f"paraview_check: {len(times_pv)} times, {times_pv[0]:.4e} .. {times_pv[-1]:.4e} s, equal to the .pvd")

# pmfrag's own count of fragments (>= 1 particle) per frame time.
timeline = {}
with open(run / "fragments_timeline.csv") as f:
    for row in csv.DictReader(f):
        timeline[float(row["time_s"])] = int(row["fragments"])

counts = []
n_particles = None
for t in times_pv:
    UpdatePipeline(time=t, proxy=reader)
    data = servermanager.Fetch(reader)
    pd = data.GetPointData()
    arr = pd.GetArray("fragment_id")
    if arr is None:
        fail(f"no point array fragment_id at t = {t}")
    for name in ("id", "phase", "displacement", "velocity", "damage", "fragment_size"):
        if pd.GetArray(name) is None:
            fail(f"no point array {name} at t = {t}")
    n = data.GetNumberOfPoints()
    if n_particles is None:
        n_particles = n
    elif n != n_particles:
        fail(f"{n} points at t = {t}, {n_particles} at the first frame")
    ids = {int(arr.GetTuple1(i)) for i in range(arr.GetNumberOfTuples())}
    counts.append(len(ids))
    key = min(timeline, key=lambda k: abs(k - t)) if timeline else None
    if key is None or abs(key - t) > 1e-9:
        fail(f"fragments_timeline.csv has no row for t = {t}")
    if timeline[key] != len(ids):
        fail(f"t = {t}: {len(ids)} distinct fragment_id in ParaView, {timeline[key]} in fragments_timeline.csv")

first_split = next((t for t, c in zip(times_pv, counts) if c >= 2), None)
print(f"paraview_check: {n_particles} particles in every frame; fragment_id read at all {len(counts)} times")
print(f"paraview_check: fragments {counts[0]} at t = {times_pv[0]:.4e} s, {counts[-1]} at t = {times_pv[-1]:.4e} s;"
      f" first frame with >= 2: {first_split if first_split is None else f'{first_split:.4e} s'}")
print("paraview_check: OK (ParaView's counts equal fragments_timeline.csv at every frame)")

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
print(f"paraview_check: particles_view.py: body at pixels x {got_x}, y {got_y} of {side}^2 where the frames' camera"
      f" puts it ({want_x[0]:.1f}..{want_x[1]:.1f}, {want_y[0]:.1f}..{want_y[1]:.1f}); mean colour"
      f" {red / n:.0f}, {green / n:.0f}, {blue / n:.0f} (orange: fragment 0)")
print("paraview_check: OK (particles_view.py shows the run under the frames' camera, coloured by fragment_id)")
