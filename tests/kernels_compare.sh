#!/usr/bin/env bash
# The same scenes through two builds (CI: the plain build and the portable-kernel one). Where the two builds
# run different bond kernels (AVX-512 sweeps against portable loops) the final positions must agree to
# round-off, 1e-9 cm; where they run the same kernels (a machine without AVX-512), bitwise.
#   bash tests/kernels_compare.sh PMFRAG_A PMFRAG_B SOURCE_DIR
set -euo pipefail
a=$1 b=$2 src=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# scene, name, --set items: the bonded plate's quiet phase (one law: the fixed-law sweep), the same plate with a
# law of the (p,q) sweep (its exponents from the sweep table) and with laws beyond it (run-time exponents; q = 2p
# and not), the inclusion (several laws: the many-law sweep), the 3-D block (the 3-D stencil), each short of its
# first broken bond
cases=("slit_plate_7_14.toml plate time.end=5e-3"
       "slit_plate_7_14.toml plate_4_9 phase.0.p=4 phase.0.q=9 time.dt=\"auto\" time.end=5e-3"
       "slit_plate_7_14.toml plate_16_32 phase.0.p=16 phase.0.q=32 time.dt=\"auto\" time.end=2e-3"
       "slit_plate_7_14.toml plate_31_64 phase.0.p=31 phase.0.q=64 time.dt=\"auto\" time.end=1e-3"
       "inclusion.toml inclusion time.end=2e-3"
       "block3d_slit.toml block time.end=2e-5")
names=()
for c in "${cases[@]}"; do
  read -r scene name rest <<< "$c"
  read -ra items <<< "$rest"
  names+=("$name")
  sets=()
  for s in "${items[@]}"; do sets+=(--set "$s"); done
  for side in a b; do
    bin=$a
    [[ $side == b ]] && bin=$b
    "$bin" run "$src/cases/$scene" --out "$work/$name.$side" -q --force "${sets[@]}" > /dev/null
  done
done
/usr/bin/python3 - "$work" "${names[@]}" <<'PY'
import json, sys
import h5py
import numpy as np
work = sys.argv[1]
bad = 0
for name in sys.argv[2:]:
    kernels, final = [], []
    for side in ("a", "b"):
        kernels.append(json.load(open(f"{work}/{name}.{side}/run.json"))["kernels"])
        with h5py.File(f"{work}/{name}.{side}/trajectory.h5", "r") as h5:
            final.append(h5["particles/all/position/value"][-1])
    diff = float(np.abs(final[0] - final[1]).max())
    same = kernels[0] == kernels[1]
    limit = 0.0 if same else 1e-9
    ok = diff <= limit
    bad += not ok
    print(f"{name}: {kernels[0]} against {kernels[1]} kernels: final positions differ by at most {diff:.3g} cm "
          f"({'must be bitwise equal' if same else 'limit 1e-9 cm'}): {'ok' if ok else 'FAILED'}")
sys.exit(1 if bad else 0)
PY
