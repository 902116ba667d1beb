#!/usr/bin/python3
"""MDAnalysis (Debian's python3-mdanalysis) opens `pmfrag export RUN --format mdanalysis` of a 2-D and a 3-D run,
with no topology and no options, and its frames are the trajectory's: positions and velocities of frame k equal
h5py's reading of trajectory.h5 within MDAnalysis' one rounding to 32-bit floats, in its units (Angstrom, ps).

Usage: mdanalysis_check.py PMFRAG SOURCE_DIR
"""
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import h5py
import numpy as np

warnings.simplefilter("ignore", DeprecationWarning)  # MDAnalysis 2.4 imports xdrlib
import MDAnalysis as mda  # noqa: E402

pmfrag, src = sys.argv[1], Path(sys.argv[2])
# scene, overrides: a 2-D plate run long enough for bonds to break, and a small 3-D block
runs = {
    "2-D": ("cases/slit_plate_7_14.toml", ["--set", "time.end=1.2e-2", "--set", "output.every=1e-3"]),
    "3-D": ("cases/block3d_slit.toml", ["--set", "body.0.sites=[12,16,6]", "--set", "time.end=2e-4",
                                        "--set", "output.every=5e-5"]),
}
CM = 1e8         # Angstrom per cm
CM_S = 1e-4      # Angstrom/ps per cm/s
ULP = 2.0 ** -24  # one rounding to float32, relative
with tempfile.TemporaryDirectory() as tmp:
    for label, (scene, extra) in runs.items():
        out = Path(tmp) / label
        subprocess.run([pmfrag, "run", str(src / scene), "--out", str(out), "-q", *extra], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run([pmfrag, "export", str(out), "--format", "mdanalysis", "--every", "2"], check=True,
                       stdout=subprocess.DEVNULL)
        f = h5py.File(out / "trajectory.h5", "r")
        x, v = f["particles/all/position/value"], f["particles/all/velocity/value"]
        t, step = f["particles/all/position/time"][:], f["particles/all/position/step"][:]
        dim = x.shape[2]
        kept = [k for k in range(x.shape[0]) if k % 2 == 0 or k == x.shape[0] - 1]

        u = mda.Universe(str(out / "mdanalysis" / "trajectory.h5md"))
        assert u.atoms.n_atoms == x.shape[1], (u.atoms.n_atoms, x.shape)
        assert len(u.trajectory) == len(kept), (len(u.trajectory), kept)
        assert u.trajectory.units == {"time": "s", "length": "Angstrom", "velocity": "Angstrom/ps", "force": None}, \
            u.trajectory.units
        worst = 0.0
        for ts, k in zip(u.trajectory, kept):
            ref = np.zeros((x.shape[1], 3))
            ref[:, :dim] = x[k]
            err = np.abs(ts.positions.astype(np.float64) / CM - ref)
            assert np.all(err <= ULP * np.abs(ref) + 1e-300), f"{label} frame {k}: {err.max():.3g} cm"
            worst = max(worst, err.max())
            vref = np.zeros((x.shape[1], 3))
            vref[:, :dim] = v[k]
            verr = np.abs(ts.velocities.astype(np.float64) / CM_S - vref)
            assert np.all(verr <= 2 * ULP * np.abs(vref) + 1e-300), f"{label} frame {k} velocities: {verr.max():.3g} cm/s"
            assert abs(ts.time - t[k] * 1e12) <= 1e-9 * max(1.0, t[k] * 1e12), (ts.time, t[k])  # ps
            assert ts.data["step"] == step[k]
            assert ts.dimensions is None  # the body is free in space: no periodic box
        moved = np.abs(x[kept[-1]] - x[0]).max()
        assert moved > 1e-4, f"{label}: nothing moved ({moved})"
        print(f"{label}: MDAnalysis reads {len(kept)} frames of {x.shape[1]} particles; positions within "
              f"{worst:.2e} cm of h5py's (largest coordinate {np.abs(x[...]).max():.3g} cm)")
    print("MDAnalysis opens pmfrag's 2-D and 3-D exports and reads the trajectory's frames")
