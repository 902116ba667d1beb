#!/usr/bin/env bash
# pmfrag study modulus: the fitted 2-D modulus of a triangular lattice of nearest-neighbour springs is
# 2/sqrt(3) x S0/r0 (thickness r0) with Poisson ratio 1/3; on the 2135-particle plate the free edges take a
# few per cent off. In 3-D an fcc lattice pulled in a close-packed plane has sqrt(2) x S0/r0 and nu = 1/3; the
# clamped faces of the small block add a few per cent.
#   modulus_test.sh PMFRAG
set -u
pmfrag=$1
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$pmfrag" study modulus --out "$d" || exit 1
/usr/bin/python3 - "$d/modulus.csv" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 6, rows
for r in rows:
    ratio, nu = float(r["ratio"]), float(r["poisson"])
    if r["dim"] == "2":
        assert 0.95 * 2 / math.sqrt(3) < ratio < 1.01 * 2 / math.sqrt(3), r
        assert abs(nu - 1 / 3) < 0.03, r
    else:
        assert 0.97 * math.sqrt(2) < ratio < 1.06 * math.sqrt(2), r
        assert abs(nu - 1 / 3) < 0.04, r
    assert float(r["fit_rms_rel"]) < 0.01, r
print("ok: 2-D and 3-D moduli and Poisson ratios as triangular and fcc spring lattices")
PY
