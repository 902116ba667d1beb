"""LAMMPS as pmfrag's engine beyond one machine: `pmfrag lammps` -> `mpirun -np 2 lmp` -> `pmfrag import` ->
`pmfrag fragments`, on the slit plate under both readings of the model, against pmfrag's own run of the same
scene. Asserted: positions at 2e-3 s within 1e-6 cm; the first broken bond within one frame (the import dates a
bond event by the first frame that shows it); the same fragments and broken bonds at the end; export and render
read the imported run. Then bad input: a scene LAMMPS cannot run, a folder that is not a deck, a dump cut short
(read as partial), a dump with a broken line (refused naming file and line).
    python3 tests/lammps_bridge_test.py PMFRAG SOURCE_DIR
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

pmfrag, src = sys.argv[1], Path(sys.argv[2])
if shutil.which("lmp") is None:
    print("skip: no lmp (scripts/install-deps installs Debian's lammps)")
    sys.exit(77)
work = Path(tempfile.mkdtemp())
plate = src / "cases/slit_plate_7_14.toml"
failed = False


def check(name, ok, detail=""):
    global failed
    print(("ok: " if ok else "FAIL: ") + name + (f" ({detail})" if detail else ""))
    failed |= not ok


def sh(*cmd, cwd=None, ok=True):
    p = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True)
    if ok and p.returncode != 0:
        print(f"FAIL: {' '.join(map(str, cmd))} exited {p.returncode}:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
        sys.exit(1)
    return p


mpirun = ["mpirun", "-np", "2"] + (["--allow-run-as-root", "--oversubscribe"] if os.getuid() == 0 else [])


def last_row(run):
    with open(run / "fragments_timeline.csv") as f:
        return list(csv.DictReader(f))[-1]


def sizes(run):
    with open(run / "fragments_final.csv") as f:
        return sorted(int(r["particles"]) for r in csv.DictReader(f))


for model, end in (("bonded", "1.5e-2"), ("cutoff", "1e-2")):
    sets = ["--set", f"pair.model={model}", "--set", f"time.end={end}"]
    deck, imported, own = work / f"deck_{model}", work / f"imported_{model}", work / f"pmfrag_{model}"
    sh(pmfrag, "lammps", plate, "--out", deck, *sets)
    sh(*mpirun, "lmp", "-in", "in.lammps", "-log", "log.lammps", cwd=deck)
    out = sh(pmfrag, "import", deck, "--out", imported).stdout
    steps = round(float(end) / 1e-7)
    check(f"{model}: import reads the whole run", "PARTIAL" not in out and f"(steps 0..{steps} of {steps})" in out,
          out.strip())
    sh(pmfrag, "run", plate, "--out", own, "-q", *sets)
    for run in (own, imported):
        sh(pmfrag, "fragments", run)
    with h5py.File(own / "trajectory.h5") as a, h5py.File(imported / "trajectory.h5") as b:
        ta, tb = a["particles/all/position/time"][:], b["particles/all/position/time"][:]
        k = int(np.argmin(abs(ta - 2e-3)))
        kb = int(np.argmin(abs(tb - 2e-3)))
        dx = float(np.abs(a["particles/all/position/value"][k] - b["particles/all/position/value"][kb]).max())
    check(f"{model}: positions at t = 2e-3 s within 1e-6 cm of pmfrag's", abs(ta[k] - 2e-3) < 1e-12 and dx < 1e-6,
          f"max |dx| = {dx:.3g} cm")
    t_own = json.loads((own / "run.json").read_text())["first_break_time_s"]
    t_lmp = json.loads((imported / "run.json").read_text())["first_break_time_s"]
    check(f"{model}: the first broken bond within one frame (1e-4 s)", 0 < t_own <= t_lmp < t_own + 1e-4 + 1e-12,
          f"pmfrag {t_own:.6g} s at its step, LAMMPS by the frame at {t_lmp:.6g} s")
    ra, rb = last_row(own), last_row(imported)
    check(f"{model}: the same fragments at the end", sizes(own) == sizes(imported) and ra["fragments"] == rb["fragments"],
          f"pmfrag {sizes(own)}, LAMMPS {sizes(imported)}")
    check(f"{model}: the same broken bonds at the end", ra["broken_bonds"] == rb["broken_bonds"],
          f"pmfrag {ra['broken_bonds']}, LAMMPS {rb['broken_bonds']}")
    if model == "bonded":
        check("export reads the imported run", sh(pmfrag, "export", imported, "--every", "50", ok=False).returncode == 0)
        check("render reads the imported run",
              sh(pmfrag, "render", imported, "--every", "50", "--size", "128", ok=False).returncode == 0)

# --- bad input --------------------------------------------------------------------------------------------
p = sh(pmfrag, "lammps", plate, "--out", work / "refused", "--set", "damping.gamma=10", ok=False)
check("a scene with an effect LAMMPS lacks is refused, naming it, and no deck is written",
      p.returncode != 0 and "[damping] cannot be written for LAMMPS" in p.stderr and not (work / "refused").exists(),
      p.stderr.strip())
p = sh(pmfrag, "import", src / "cases", "--out", work / "not_a_deck", ok=False)
check("import of a folder that is not a deck is refused, naming it",
      p.returncode != 0 and "not a LAMMPS deck" in p.stderr and str(src / "cases") in p.stderr, p.stderr.strip())
deck = work / "deck_bonded"
whole = (deck / "frames.dump").read_bytes()
(deck / "frames.dump").write_bytes(whole[: len(whole) * 2 // 3])  # a run killed two thirds of the way
p = sh(pmfrag, "import", deck, "--out", work / "cut", ok=False)
check("a dump cut short is read up to its last whole frame, marked PARTIAL",
      p.returncode == 0 and "(PARTIAL)" in p.stdout and "stopped at step 99000 of 150000 in LAMMPS (frames.dump ends inside the frame" in p.stdout, p.stdout.strip())
f = sh(pmfrag, "fragments", work / "cut", ok=False)
check("and fragments says the run is partial", f.returncode == 0 and "PARTIAL" in f.stdout + f.stderr,
      (f.stdout + f.stderr)[-300:])
lines = whole.decode().split("\n")
lines[12] = "1 0.5 oops"
(deck / "frames.dump").write_text("\n".join(lines))
p = sh(pmfrag, "import", deck, "--out", work / "broken", "--force", ok=False)
check("a broken line in the dump is refused, naming the file and line",
      p.returncode != 0 and "frames.dump:13:" in p.stderr, p.stderr.strip())
shutil.rmtree(work)
sys.exit(1 if failed else 0)
