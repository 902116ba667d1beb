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

