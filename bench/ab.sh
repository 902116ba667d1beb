#!/usr/bin/env bash
# Two builds of pmfrag side by side on the scenes whose speed a change must keep: the bonded (7,14) plate on
# one and on two threads (forced), and the 3-D block (bonded, 54,940 particles) on two threads.
#   bash bench/ab.sh OLD_PMFRAG NEW_PMFRAG
# Each round runs OLD then NEW on one scene, so the two of a pair see the machine in one state; the ratio
# NEW/OLD is the median of the pairs' ratios (REPS pairs, default 5), with their range.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -eq 2 ] || { echo "usage: bash bench/ab.sh OLD_PMFRAG NEW_PMFRAG" >&2; exit 2; }
old=$1
new=$2
reps=${REPS:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/lib.sh
rate() {  # rate BIN THREADS SCENE [--set ...] -> particle-steps/s of one run
  local bin=$1 threads=$2 scene=$3
  shift 3
  env PMFRAG_MIN_PARTICLES_PER_THREAD=1 "$bin" run "$scene" --out "$work/run" --force -q --threads "$threads" "$@" \
    > /dev/null
  sed -n 's/.*"particle_steps_per_s": *\([0-9.e+-]*\).*/\1/p' "$work/run/run.json"
}
echo "processor: $(processor), $(nproc) cores; $(date -u +%F); $reps pairs a row"
echo "old: $old"
echo "new: $new"
printf '%-44s %7s %11s %11s %7s %s\n' scene threads old new new/old "pairs' range"
row() {  # row LABEL THREADS SCENE [--set ...]
  local label=$1 threads=$2
  shift 2
  : > "$work/pairs"
  for _ in $(seq "$reps"); do
    echo "$(rate "$old" "$threads" "$@") $(rate "$new" "$threads" "$@")" >> "$work/pairs"
  done
  printf '%-44s %7s %11.3g %11.3g %7.3f %s\n' "$label" "$threads" "$(awk '{print $1}' "$work/pairs" | median)" \
    "$(awk '{print $2}' "$work/pairs" | median)" "$(awk '{printf "%.4f\n", $2 / $1}' "$work/pairs" | median)" \
    "$(awk '{printf "%.3f\n", $2 / $1}' "$work/pairs" | sort -g | sed -n '1p;$p' | paste -sd-)"
}
row "plate (7,14) bonded, 0 to 2e-3 s" 1 cases/slit_plate_7_14.toml --set time.end=2e-3 --set output.every=1
row "plate (7,14) bonded, 0 to 2e-3 s" 2 cases/slit_plate_7_14.toml --set time.end=2e-3 --set output.every=1
row "3-D block bonded, 54,940 particles, 1,000 steps" 2 cases/block3d_slit.toml --set time.end=1e-4 \
  --set output.every=1
