#!/usr/bin/python3
"""An independent reader (h5py) opens a pmfrag trajectory and checks the H5MD layout, times and positions.

Usage: h5md_independent_check.py PMFRAG SOURCE_DIR
"""
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

pmfrag, src = sys.argv[1], Path(sys.argv[2])
with tempfile.TemporaryDirectory() as tmp:
    out = Path(tmp) / "run"
    subprocess.run([pmfrag, "run", str(src / "cases/slit_plate_7_14.toml"), "--out", str(out), "-q",
                    "--set", "time.end=2e-4", "--set", "output.every=5e-5"], check=True, stdout=subprocess.DEVNULL)
    f = h5py.File(out / "trajectory.h5", "r")
    assert list(f["h5md"].attrs["version"]) == [1, 1], "H5MD version"
    # text attributes are variable-length UTF-8 (h5py gives str, not bytes), as MDAnalysis needs them
    assert f["h5md/creator"].attrs["name"] == "pmfrag", f["h5md/creator"].attrs["name"]
    assert f["particles/all/position/value"].attrs["unit"] == "cm"
    assert list(f["particles/all/box"].attrs["boundary"]) == ["none"] * 2
    pos = f["particles/all/position"]
    x, t, step = pos["value"][:], pos["time"][:], pos["step"][:]
    assert x.shape == (5, 2698, 2), x.shape
    assert np.allclose(t, [0, 5e-5, 1e-4, 1.5e-4, 2e-4], rtol=0, atol=1e-15), t
    assert list(step) == [0, 500, 1000, 1500, 2000], step
    # Greenspan's site 1 at (-3.9, -5.71576764), and the top row moved up by 20 cm/s x t
    assert np.allclose(x[0, 0], [-3.9, -5.71576764], atol=1e-12), x[0, 0]
    top = x[0, :, 1] > x[0, :, 1].max() - 0.05
    assert top.sum() == 40
    assert np.allclose(x[-1, top, 1] - x[0, top, 1], 20 * 2e-4, rtol=1e-9)
    assert np.allclose(x[-1, top, 0], x[0, top, 0], atol=1e-15)
    assert f["connectivity/bonds"].shape == (7850, 2)
    assert f["particles/all/box"].attrs["dimension"] == 2
    assert abs(f["parameters/dt"][()] - 1e-7) < 1e-20
    assert abs(f["parameters/G"][()] / 1.102308e5 - 1) < 1e-6
    e = f["observables/total_energy/value"][:]
    assert e.shape == (5,)
    print("h5py reads the trajectory: layout, times, positions and parameters as expected")
