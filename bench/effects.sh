#!/usr/bin/env bash
# What declared effects cost: the bonded (7,14) slit plate with pair + kinematic alone, and with gravity,
# damping and greenspan_alpha declared as well. Pairs of runs alternate (plain, every effect), so the two of a
# pair see the machine in one state; the ratio is the median of the pairs' ratios.
#   bash bench/effects.sh [PMFRAG ...]
# With several binaries (e.g. one built before a change and one after), each runs its pairs in turn within
# the same rounds, so their ratios are side by side. Default: build/app/pmfrag. REPS pairs (default 5).
# Threads: "1" is one thread; "2" forces the plate (2,698 particles) onto two, as a bigger body runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bins=("$@")
if [ ${#bins[@]} -eq 0 ]; then
  bash scripts/build > /dev/null
  bins=("$PWD/build/app/pmfrag")
fi
reps=${REPS:-5}
end=${END:-2e-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/lib.sh
rate() {  # rate BIN THREADS [--set ...] -> particle-steps/s of one run
  local bin=$1 threads=$2
  shift 2
  local env=()
  [ "$threads" = 2 ] && env=(env PMFRAG_MIN_PARTICLES_PER_THREAD=1)
  "${env[@]}" "$bin" run cases/slit_plate_7_14.toml --out "$work/run" --force -q --threads "$threads" \
    --set time.end="$end" --set output.every=1 "$@" > /dev/null
  sed -n 's/.*"particle_steps_per_s": *\([0-9.e+-]*\).*/\1/p' "$work/run/run.json"
}
every=(--set 'gravity.g=[0,-980]' --set damping.gamma=1.0 --set greenspan_alpha.enabled=true)
echo "processor: $(processor), $(nproc) cores; $(date -u +%F)"
echo "scene: cases/slit_plate_7_14.toml (bonded, 2,698 particles), 0 to $end s; $reps alternated pairs"
printf '%-40s %7s %14s %14s %7s\n' binary threads "pair+kin" "+3 effects" ratio
for threads in 1 2; do
  for b in "${!bins[@]}"; do : > "$work/pairs.$b"; done
  for _ in $(seq "$reps"); do
    for b in "${!bins[@]}"; do
      plain=$(rate "${bins[$b]}" "$threads")
      all=$(rate "${bins[$b]}" "$threads" "${every[@]}")
      echo "$plain $all" >> "$work/pairs.$b"
    done
  done
  for b in "${!bins[@]}"; do
    p=$(awk '{print $1}' "$work/pairs.$b" | median)
    a=$(awk '{print $2}' "$work/pairs.$b" | median)
    r=$(awk '{printf "%.4f\n", $2 / $1}' "$work/pairs.$b" | median)
    printf '%-40s %7s %14.3g %14.3g %7.2f\n' "$(basename "$(dirname "${bins[$b]}")")/$(basename "${bins[$b]}")" \
      "$threads" "$p" "$a" "$r"
  done
done
