"""`pmfrag export RUN --paraview-script` writes RUN/particles_view.py; this runs it against a stand-in for
ParaView's `paraview.simple` that records what the script asks of ParaView (the real ParaView runs it in
scripts/paraview-check). Checked: it opens the collection beside itself, also after the folder moved; it colours
by fragment_id as categories with pmfrag's palette; it sets, after ParaView's first render, a camera that frames
the first frame's body as pmfrag's frames do (recomputed here from the trajectory with h5py); the screenshot
gets the size and time asked; a bad option is refused.
    python3 tests/paraview_script_test.py PMFRAG SOURCE_DIR
"""
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py

pmfrag, src = sys.argv[1], Path(sys.argv[2])
work = Path(tempfile.mkdtemp())
failed = False


def check(name, ok, detail=""):
    global failed
    print(("ok: " if ok else "FAIL: ") + name + ("" if ok else f" ({detail})"))
    failed |= not ok


STUB = '''
import json, os, xml.etree.ElementTree as ET
log = []
renders = [0]
class Proxy:
    def __init__(self, kind, **kw):
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "props", dict(kw))
    def __setattr__(self, k, v):
        self.props[k] = v
        log.append({"set": self.kind, "key": k, "value": v, "after_renders": renders[0]})
    def __getattr__(self, k):
        if k in self.props: return self.props[k]
        if not k.startswith(("Set", "Update")): raise AttributeError(k)  # a property never set (hasattr)
        return lambda *a, **kw: log.append({"call": self.kind + "." + k, "args": [repr(x) for x in a]})
class Array:
    def __init__(self, hi): self.hi = hi
    def GetRange(self): return (0.0, self.hi)
def PVDReader(registrationName=None, FileName=None):
    log.append({"reader": FileName})
    times = [float(d.get("timestep")) for d in ET.parse(FileName).getroot().iter("DataSet")]
    p = Proxy("reader", FileName=FileName)
    p.props["TimestepValues"] = times
    p.props["PointData"] = {"fragment_id": Array(float(os.environ["FRAGMENTS"]) - 1)}
    return p
view = Proxy("view", UseColorPaletteForBackground=1)
lut = Proxy("lut")
scene = Proxy("scene")
def GetActiveViewOrCreate(kind): return view
def GetActiveView(): return view
def Show(source, v=None): return Proxy("display:" + source.kind)
def Text(registrationName=None, Text=""): return Proxy("text", Text=Text)
def ColorBy(display, what): log.append({"colorby": list(what)})
def GetColorTransferFunction(name): log.append({"lut": name}); return lut
def GetAnimationScene(): return scene
def GetScalarBar(l, v=None): return Proxy("bar")
def Render(v=None): renders[0] += 1
def SaveScreenshot(path, v, ImageResolution=None):
    log.append({"screenshot": path, "size": ImageResolution, "time": view.props.get("ViewTime")})
import atexit
atexit.register(lambda: json.dump(log, open(os.environ["STUB_LOG"], "w")))
'''
stub = work / "stub" / "paraview"
stub.mkdir(parents=True)
(stub / "__init__.py").write_text("")
(stub / "simple.py").write_text(STUB)

run = work / "plate"
subprocess.run([pmfrag, "run", str(src / "cases/slit_plate_7_14.toml"), "--out", str(run), "-q", "--set",
                "time.end=1e-3"], check=True, stdout=subprocess.DEVNULL)
subprocess.run([pmfrag, "export", str(run), "--paraview-script", "--every", "5"], check=True, stdout=subprocess.DEVNULL)
refused = subprocess.run([pmfrag, "export", str(run), "--format", "mdanalysis", "--paraview-script"],
                         capture_output=True, text=True)
check("--paraview-script with --format mdanalysis is refused", refused.returncode != 0 and
      "--paraview-script applies to --format vtk only" in refused.stderr, refused.stderr)

moved = work / "moved"
run.rename(moved)  # the script finds the collection beside itself
script = moved / "particles_view.py"
times = [float(d.get("timestep")) for d in ET.parse(moved / "particles.pvd").getroot().iter("DataSet")]


def run_script(*args, fragments=3):
    import json
    import os
    logfile = work / "log.json"
    env = dict(os.environ, PYTHONPATH=str(work / "stub"), STUB_LOG=str(logfile), FRAGMENTS=str(fragments))
    p = subprocess.run([sys.executable, str(script), *args], env=env, capture_output=True, text=True)
    return p, (json.loads(logfile.read_text()) if p.returncode == 0 else [])


p, log = run_script("--screenshot", str(work / "view.png"), "--size", "300")
check("the script runs", p.returncode == 0, p.stderr)
check("it opens particles.pvd beside itself after the folder moved",
      [e["reader"] for e in log if "reader" in e] == [str(moved / "particles.pvd")], log[:2])
check("it colours by fragment_id", {"colorby": ["POINTS", "fragment_id"]} in log)
sets = {(e["set"], e["key"]): e for e in log if "set" in e}
check("as categories", sets.get(("lut", "InterpretValuesAsCategories"), {}).get("value") == 1)
colours = sets[("lut", "IndexedColors")]["value"]
check("one colour per fragment of the last frame, pmfrag's orange first",
      len(colours) == 9 and [round(c, 3) for c in colours[:3]] == [0.902, 0.624, 0.0], colours[:6])
check("the legend is shown for a few fragments",
      any(e.get("call") == "display:reader.SetScalarBarVisibility" and e["args"][-1] == "True" for e in log))
check("the legend's text is dark on the white background",
      sets.get(("bar", "TitleColor"), {}).get("value") == [0.1, 0.1, 0.1] and
      sets.get(("bar", "LabelColor"), {}).get("value") == [0.1, 0.1, 0.1], [k for k in sets if k[0] == "bar"])

# The frames' camera, recomputed from the first frame: parallel, the body's box with a 20 % margin plus a disc
# radius, the focal point 4 % of the scale above the box's centre.
with h5py.File(moved / "trajectory.h5", "r") as f:
    r = f["particles/all/position/value"][0]
    r0 = float(f["parameters/r0"][()])
x0, x1, y0, y1 = r[:, 0].min(), r[:, 0].max(), r[:, 1].min(), r[:, 1].max()
scale = 1.2 * max(0.5 * (y1 - y0), 0.5 * (x1 - x0)) + 0.45 * r0
focal = [0.5 * (x0 + x1), 0.5 * (y0 + y1) + 0.04 * scale, 0.0]
cam = {k: sets.get(("view", k), {}) for k in ("CameraParallelScale", "CameraFocalPoint", "CameraParallelProjection")}
check("the camera is parallel, set after ParaView's first render",
      cam["CameraParallelProjection"].get("value") == 1 and cam["CameraParallelProjection"].get("after_renders", 0) >= 1,
      cam)
check("its scale and focal point frame the body as pmfrag's frames do",
      abs(cam["CameraParallelScale"].get("value", 0) - scale) < 1e-9 * scale and
      all(abs(a - b) < 1e-9 * scale for a, b in zip(cam["CameraFocalPoint"].get("value", []), focal)),
      f"{cam} against scale {scale}, focal {focal}")
shots = [e for e in log if "screenshot" in e]
check("the screenshot has the size asked, at the last frame",
      len(shots) == 1 and shots[0]["size"] == [300, 300] and abs(shots[0]["time"] - times[-1]) < 1e-15, shots)

p, log = run_script("--screenshot", str(work / "first.png"), "--time", repr(times[0]), fragments=200)
shots = [e for e in log if "screenshot" in e]
check("--time picks the frame", len(shots) == 1 and shots[0]["time"] == times[0], shots)
check("with many fragments, no legend",
      any(e.get("call") == "display:reader.SetScalarBarVisibility" and e["args"][-1] == "False" for e in log))
p, _ = run_script("--frame", "3")
check("a bad option is refused, naming it", p.returncode != 0 and "'--frame'" in p.stderr, p.stderr)
sys.exit(1 if failed else 0)
