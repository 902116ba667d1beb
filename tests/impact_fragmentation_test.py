#!/usr/bin/python3
"""A disc shattered against a fixed wall (cases/disc_wall_impact.toml), and the same disc at a twentieth of the
speed: the wall stays put, the energy balance holds, the fast disc breaks into many pieces with a fitted mass
exponent, the slow one stays whole.

Usage: impact_fragmentation_test.py PMFRAG SOURCE_DIR
"""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

pmfrag, src = sys.argv[1], Path(sys.argv[2])
scene = src / "cases/disc_wall_impact.toml"


def run(out, sets):
    subprocess.run([pmfrag, "run", str(scene), "--out", str(out), "-q"] + sum([["--set", s] for s in sets], []),
                   check=True, capture_output=True)
    text = subprocess.run([pmfrag, "fragments", str(out)], check=True, capture_output=True, text=True).stdout
    summary = json.loads((out / "summary.json").read_text())
    with h5py.File(out / "trajectory.h5", "r") as h5:
        x = h5["particles/all/position/value"]
        wall = h5["particles/all/body"][:] == 1
        moved = float(np.abs(x[-1][wall] - x[0][wall]).max())
        obs = h5["observables"]
        balance, ke = obs["energy_balance/value"][:], obs["kinetic_energy/value"][:]
        drift = float(np.abs(balance - balance[0]).max() / ke[0])
    return summary, text, moved, drift


with tempfile.TemporaryDirectory() as tmp:
    fast, text, moved, drift = run(Path(tmp) / "fast", [])
    print(text)
    print(f"1,000 m/s: wall moved {moved:.3g} cm, |balance - balance_0| <= {drift:.3g} of the impact energy")
    assert moved == 0.0, "the wall held in place must not move"
    assert fast["target_particles"] == 723 and fast["particles"] == 5099, fast
    assert fast["fragments_2plus"] >= 20, fast
    d = fast["distribution"]
    assert d is not None, fast["distribution_note"]
    assert d["exponent_ci"][0] < d["exponent"] < d["exponent_ci"][1] and d["fragments_fitted"] >= 10, d
    assert drift < 5e-3, drift

    slow, text, moved, drift = run(Path(tmp) / "slow", ["impactor.0.velocity=[0.0,-5000.0]", "time.end=2e-3"])
    print(text)
    print(f"50 m/s: wall moved {moved:.3g} cm, |balance - balance_0| <= {drift:.3g} of the impact energy")
    assert moved == 0.0
    assert slow["fragments"] < fast["fragments"] and slow["largest_mass_fraction"] > 0.9, slow
    assert slow["distribution"] is None and "at least 10" in slow["distribution_note"], slow
    assert drift < 5e-3, drift
print("the disc shatters against the fixed wall at 1,000 m/s and stays whole at 50 m/s")
