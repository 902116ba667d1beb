#!/usr/bin/env python3
"""Write LAMMPS inputs that run the same particles, law and loading as a pmfrag scene.

Usage: lammps_inputs.py DATA_FILE STEPS OUTDIR   (reads DATA_FILE.params from `pmfrag scene --lammps-data`)

Two inputs, one per reading of the model (docs/physics.md):
  cutoff.in  - pair_style mie/cut: every pair within D interacts. Mie with gamma_R = q-1, gamma_A = p-1 and
               eps, sigma chosen so that its force is exactly -G/r^p + H/r^q.
  bonded.in  - the original bonds through bond_style table (the same law, tabulated finely), and mie/cut only
               up to r0 for non-bonded contacts (special_bonds excludes bonded pairs), as pmfrag's bonded model.
  cutoff_tight.in - cutoff.in with the skin pmfrag starts from (3/4 of the gap between D and the next lattice
               shell at sqrt(3) r0): fewer pairs per step, more rebuilds; the bench takes LAMMPS' faster skin.
Kinematic rows are atom types 2 and 3 (pmfrag scene --lammps-data writes them): velocity set + setforce 0.
"""
import math
import sys
from pathlib import Path

data, steps, out = sys.argv[1:4]
p, q, G, H, mass, r0, cutoff, dt, dim = open(data + ".params").read().split()
p, q, steps, dim = int(p), int(q), int(steps), int(dim)
G, H, mass, r0, cutoff, dt = map(float, (G, H, mass, r0, cutoff, dt))
out = Path(out)
out.mkdir(parents=True, exist_ok=True)

# Mie: E = C eps [(s/r)^gR - (s/r)^gA], C = gR/(gR-gA) (gR/gA)^(gA/(gR-gA)); F = -dE/dr.
gR, gA = q - 1, p - 1
C = gR / (gR - gA) * (gR / gA) ** (gA / (gR - gA))
sigma = (H * (p - 1) / (G * (q - 1))) ** (1.0 / (q - p))
eps = G / ((p - 1) * C * sigma ** gA)


def force(r):
    return -G / r ** p + H / r ** q


def energy(r):
    return G * r ** (1 - p) / (1 - p) - H * r ** (1 - q) / (1 - q)


# bond table from 0.5 r0 to D (bonds never get closer than 0.5 r0 in these runs)
n = 20000
lo, hi = 0.5 * r0, cutoff
with open(out / "bond.table", "w") as f:
    f.write(f"# (p,q) = ({p},{q}) law, written by pmfrag bench\nPQ\nN {n}\n\n")
    for k in range(n):
        r = lo + (hi - lo) * k / (n - 1)
        f.write(f"{k + 1} {r:.12g} {energy(r):.16g} {force(r):.16g}\n")

common = f"""units cgs
dimension {dim}
boundary s s {'p' if dim == 2 else 's'}
atom_style bond
read_data {Path(data).resolve()}
neighbor {0.3 * r0} bin
neigh_modify every 1 delay 0 check yes
group top type 2
group bottom type 3
velocity top set 0 20 0
velocity bottom set 0 -20 0
fix move all nve
fix hold_top top setforce 0 0 0
fix hold_bottom bottom setforce 0 0 0
{'fix flat all enforce2d' if dim == 2 else ''}
timestep {dt}
thermo {steps}
"""
(out / "cutoff.in").write_text(common.replace("atom_style bond\n", "atom_style bond\n") + f"""
pair_style mie/cut {cutoff}
pair_coeff * * {eps:.16g} {sigma:.16g} {gR} {gA}
bond_style zero
bond_coeff 1 {r0}
special_bonds lj 1 1 1
run {steps}
""")
# Both lattices (triangular, fcc) have a shell at sqrt(3) r0, the first beyond D = 1.7 r0.
tight = 0.75 * (math.sqrt(3.0) * r0 - cutoff) if math.sqrt(3.0) * r0 > cutoff else 0.3 * r0
(out / "cutoff_tight.in").write_text((out / "cutoff.in").read_text().replace(f"neighbor {0.3 * r0} bin", f"neighbor {tight} bin"))
(out / "bonded.in").write_text(common + f"""
pair_style mie/cut {r0}
pair_coeff * * {eps:.16g} {sigma:.16g} {gR} {gA}
bond_style table linear {n}
bond_coeff 1 {out.resolve() / 'bond.table'} PQ
special_bonds lj 0 1 1
run {steps}
""")
print(f"mie: eps = {eps:.10g} erg, sigma = {sigma:.10g} cm, gamma_R = {gR}, gamma_A = {gA}")
