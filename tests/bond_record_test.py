#!/usr/bin/python3
"""The engine's record of broken bonds, read with h5py (not pmfrag's reader), against what `pmfrag fragments`
reports at every frame.

Three runs where the two readings differ: a disc striking a plate at 50,000 cm/s (bonds break and their
particles are crushed back within D), a (7,14) plate with a hole (bonded), and the (7,14) slit plate under the
cutoff model (pairs leave D and come back). For each: the record replayed up to every frame's step must equal
fragments_timeline.csv's broken_bonds, the engine's pairs_beyond_cutoff, and the fragments counted here from
the replayed bonds; summary.json says "bond_state": "recorded" and broken_bonds_engine == broken_bonds.

With --damage instead: a record cut short (rows missing, as a killed run leaves it) is read up to the last frame
it covers and every output says partial; a record naming a bond that does not exist is refused, naming the
file and the dataset.

Usage: bond_record_test.py PMFRAG SOURCE_DIR [--damage]
"""
import csv
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

pmfrag, src = sys.argv[1], Path(sys.argv[2])


def components(n, bonds, intact):
    """Connected components of the intact bonds (union-find with path halving)."""
    parent = np.arange(n)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for (i, j) in bonds[intact]:
        a, b = find(i), find(j)
        if a != b:
            parent[a] = b
    return len({find(i) for i in range(n)})


def check(name, scene, sets):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / name
        run = subprocess.run([pmfrag, "run", str(scene), "--out", str(out), "-q"] + sum([["--set", s] for s in sets], []),
                             check=True, capture_output=True, text=True)
        frag = subprocess.run([pmfrag, "fragments", str(out)], check=True, capture_output=True, text=True)
        dist = subprocess.run([pmfrag, "fragments", str(out), "--break", "D"], check=True, capture_output=True,
                              text=True)
        with open(out / "fragments_timeline.csv") as f:
            distance_rows = list(csv.DictReader(f))
        subprocess.run([pmfrag, "fragments", str(out)], check=True, capture_output=True)
        with open(out / "fragments_timeline.csv") as f:
            rows = list(csv.DictReader(f))
        summary = json.loads((out / "summary.json").read_text())

        h5 = h5py.File(out / "trajectory.h5", "r")
        rec = h5["connectivity/broken_bonds"]
        model = rec.attrs["model"]
        model = model.decode() if isinstance(model, bytes) else str(model)
        ev_step, ev_bond, ev_again = rec["step"][:], rec["bond"][:], rec["re_formed"][:]
        ev_time = rec["time"][:]
        bonds = h5["connectivity/bonds"][:]
        frame_step = h5["particles/all/position/step"][:]
        frame_time = h5["particles/all/position/time"][:]
        engine = h5["observables/pairs_beyond_cutoff/value"][:]
        rows_at = rec["rows_at_frame/value"][:]
        n = h5["particles/all/position/value"].shape[1]
        dt = h5["parameters/dt"][()]

        assert np.all(np.diff(ev_step) >= 0), "events in step order"
        assert np.all((ev_bond >= 0) & (ev_bond < len(bonds))), "events name bonds of /connectivity/bonds"
        if h5["parameters/dt_adaptive"][()] == 0:
            assert np.allclose(ev_time, ev_step * dt, rtol=1e-12, atol=0), "event times are their steps'"
        assert len(rows) == len(frame_step), (len(rows), len(frame_step))
        assert summary["bond_state"] == "recorded", summary
        broken = np.zeros(len(bonds), bool)
        applied = 0
        lines = []
        for k, s in enumerate(frame_step):
            # replay every event up to this frame's step (by step, not by the writer's rows_at_frame)
            while applied < len(ev_step) and ev_step[applied] <= s:
                b = ev_bond[applied]
                assert broken[b] == bool(ev_again[applied]), f"{name}: row {applied} does not change bond {b}"
                broken[b] = not ev_again[applied]
                applied += 1
            assert rows_at[k] == applied, f"{name}: rows_at_frame[{k}] = {rows_at[k]}, replayed {applied}"
            count = int(broken.sum())
            assert int(rows[k]["broken_bonds"]) == count, f"{name} frame {k}: fragments {rows[k]['broken_bonds']}, record {count}"
            assert int(engine[k]) == count, f"{name} frame {k}: engine {engine[k]}, record {count}"
            assert int(rows[k]["broken_bonds_engine"]) == count
            if k % 5 == 0 or k == len(frame_step) - 1:  # fragments from the replayed bonds, counted here
                pieces = components(n, bonds, ~broken)
                assert int(rows[k]["fragments"]) == pieces, f"{name} frame {k}: fragments {rows[k]['fragments']}, here {pieces}"
            lines.append((frame_time[k], count, int(distance_rows[k]["broken_bonds"]), int(rows[k]["fragments"]),
                          int(distance_rows[k]["fragments"])))
        assert summary["broken_bonds_engine"] == summary["broken_bonds"], summary
        left = int((ev_again == 0).sum())
        again = int((ev_again == 1).sum())
        diff = sum(1 for l in lines if l[1] != l[2])
        print(f"{name} ({model}): {len(ev_step)} events ({left} broken / left D, {again} re-formed); "
              f"at the end {lines[-1][1]} broken by the record against {lines[-1][2]} by distance at frames, "
              f"{lines[-1][3]} fragments against {lines[-1][4]}; the readings differ at {diff} of {len(lines)} frames")
        print("  run says: " + " | ".join(l for l in run.stdout.splitlines() if "bond" in l or "cutoff" in l))
        return left, again, diff


def damage():
    with tempfile.TemporaryDirectory() as tmp:
        good = Path(tmp) / "good"
        # the (7,14) plate pulled 100x faster than the paper's: bonds break from ~1.2e-4 s; 31 frames
        subprocess.run([pmfrag, "run", str(src / "cases/slit_plate_7_14.toml"), "--out", str(good), "-q",
                        "--set", "kinematic.0.velocity=[0.0,2000.0]", "--set", "kinematic.1.velocity=[0.0,-2000.0]",
                        "--set", "time.end=3e-4", "--set", "output.every=1e-5"], check=True, capture_output=True)
        subprocess.run([pmfrag, "fragments", str(good)], check=True, capture_output=True)
        with open(good / "fragments_timeline.csv") as f:
            whole = list(csv.DictReader(f))
        with h5py.File(good / "trajectory.h5", "r") as h5:
            rows_at = h5["connectivity/broken_bonds/rows_at_frame/value"][:]
            nbonds = len(h5["connectivity/bonds"])
        assert len(whole) == 31 and rows_at[-1] > 10, (len(whole), rows_at[-1])
        with h5py.File(good / "checkpoint.h5", "r") as ck:  # the last checkpoint is taken at the last step
            assert ck["step"][()] == 3000 and ck["bond_events"][()] == rows_at[-1], (ck["step"][()], ck["bond_events"][()])

        # Cut short: keep the rows of frames 0..k-1 and half of frame k's new ones (k: the second frame with
        # new rows, so that the frames kept have some).
        k = [j for j in range(1, len(rows_at)) if rows_at[j] > rows_at[j - 1] and rows_at[j - 1] > 0][0]
        cut = Path(tmp) / "cut"
        shutil.copytree(good, cut)
        keep = int(rows_at[k - 1] + (rows_at[k] - rows_at[k - 1]) // 2)
        with h5py.File(cut / "trajectory.h5", "r+") as h5:
            for c in ("step", "time", "bond", "re_formed"):
                h5["connectivity/broken_bonds/" + c].resize((keep,))
        out = subprocess.run([pmfrag, "fragments", str(cut)], check=True, capture_output=True, text=True).stdout
        summary = json.loads((cut / "summary.json").read_text())
        with open(cut / "fragments_timeline.csv") as f:
            rows = list(csv.DictReader(f))
        assert "PARTIAL" in out and f"bond record covers frames 0..{k - 1} of 31" in out, out
        assert summary["partial"] is True and summary["frames"] == k, summary
        assert [r["broken_bonds"] for r in rows] == [r["broken_bonds"] for r in whole[:k]]
        exp = subprocess.run([pmfrag, "export", str(cut)], check=True, capture_output=True, text=True).stdout
        assert "PARTIAL" in exp and f"exported {k} of {k} frames" in exp, exp
        assert "PARTIAL" in (cut / "particles.pvd").read_text()
        print(f"a record cut short at frame {k} of 31: fragments and export read frames 0..{k - 1} and say PARTIAL")

        # A trajectory written before the record existed: read by distance at D, and summary.json says so.
        old = Path(tmp) / "old"
        shutil.copytree(good, old)
        with h5py.File(old / "trajectory.h5", "r+") as h5:
            del h5["connectivity/broken_bonds"]
        out = subprocess.run([pmfrag, "fragments", str(old)], check=True, capture_output=True, text=True).stdout
        summary = json.loads((old / "summary.json").read_text())
        assert summary["bond_state"] == "distance" and "distance reading" in out, (summary, out)
        assert summary["partial"] is False, summary
        print("a trajectory without a record: read by distance (" + summary["break_criterion"] + ")")

        # A row naming a bond that does not exist.
        bad = Path(tmp) / "bad"
        shutil.copytree(good, bad)
        with h5py.File(bad / "trajectory.h5", "r+") as h5:
            h5["connectivity/broken_bonds/bond"][3] = nbonds + 5
        r = subprocess.run([pmfrag, "fragments", str(bad)], capture_output=True, text=True)
        assert r.returncode != 0, r
        assert "trajectory.h5" in r.stderr and "/connectivity/broken_bonds/bond" in r.stderr and "row 3" in r.stderr, r.stderr
        print("a row naming bond", nbonds + 5, "is refused: " + r.stderr.strip())


if len(sys.argv) > 3 and sys.argv[3] == "--damage":
    damage()
    sys.exit(0)

impact = check("impact_50000", src / "cases/impact.toml",
               ["impactor.0.velocity=[0,-50000]", "time.end=3e-3"])
assert impact[0] > 0, "the impact must break bonds"
hole = check("hole_plate_7_14", src / "cases/slit_plate_7_14.toml",
             ['body.0.holes=[{kind="disc",center=[0.0,0.0],radius=1.0}]', "body.0.void_sites=[]",
              "time.end=1.4e-2"])
assert hole[0] > 0, "the hole plate must break"
cutoff = check("cutoff_plate_7_14", src / "cases/slit_plate_7_14.toml", ['pair.model="cutoff"', "time.end=1.4e-2"])
assert cutoff[0] > 0 and cutoff[1] > 0, "the cutoff plate must have pairs leaving D and coming back"
print("the record of broken bonds equals fragments' count at every frame of the three runs")
