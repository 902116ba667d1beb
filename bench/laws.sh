#!/usr/bin/env bash
# Every (p,q) as fast as the paper's (7,14)? The bonded slit plate, one thread, STEPS steps (default 20000).
# A law and (7,14) run at one time step, the smaller of their Eq. 15 steps ("auto"): the same number of steps
# and the same boundary travel per step (so the same list rebuilds), where each law's own step would give
# (1,2), whose step is 7x (7,14)'s, 7x the displacement per step, or in a fixed time window a seventh of the
# steps. Each law alternates with (7,14) in REPS pairs (default 3); the ratio is the median of the pairs'
# ratios (law / (7,14), particle-steps per second).
#   bash bench/laws.sh [PMFRAG] [p,q ...]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-}
if [ -z "$bin" ]; then
  bash scripts/build > /dev/null
  bin=$PWD/build/app/pmfrag
else
  shift
fi
laws=("$@")
[ ${#laws[@]} -gt 0 ] || laws=(1,2 2,3 3,5 4,9 5,10 6,12 8,16 10,20 12,24 16,32 20,40 31,64 63,64)
reps=${REPS:-3}
steps=${STEPS:-20000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/lib.sh
auto_dt() {  # auto_dt P Q -> the law's Eq. 15 step [s]
  "$bin" run cases/slit_plate_7_14.toml --out "$work/run" --force -q --threads 1 --set "phase.0.p=$1" \
    --set "phase.0.q=$2" --set 'time.dt="auto"' --set time.end=1e-5 --set output.every=1 > /dev/null
  sed -n 's/.*"dt_s": *\([0-9.e+-]*\).*/\1/p' "$work/run/run.json"
}
rate() {  # rate P Q DT -> particle-steps/s over $steps steps of DT
  "$bin" run cases/slit_plate_7_14.toml --out "$work/run" --force -q --threads 1 --set "phase.0.p=$1" \
    --set "phase.0.q=$2" --set "time.dt=$3" --set "time.end=$(awk "BEGIN{printf \"%.17g\", $steps * $3}")" \
    --set output.every=1 > /dev/null
  grep -q "\"steps\": *$steps," "$work/run/run.json" || { echo "laws.sh: ($1,$2) did not run $steps steps" >&2; exit 1; }
  sed -n 's/.*"particle_steps_per_s": *\([0-9.e+-]*\).*/\1/p' "$work/run/run.json"
}
echo "processor: $(processor); kernels: $( \
  "$bin" run cases/slit_plate_7_14.toml --out "$work/k" -q --set time.end=1e-6 > /dev/null 2>&1; \
  sed -n 's/.*"kernels": *"\([a-z0-9-]*\)".*/\1/p' "$work/k/run.json"); $(date -u +%F); $reps pairs a law, $steps steps a run"
dt_7_14=$(auto_dt 7 14)
printf '%-8s %12s %12s %8s\n' "(p,q)" "law" "(7,14)" ratio
for pq in "${laws[@]}"; do
  p=${pq%,*}
  q=${pq#*,}
  dt=$(awk -v a="$(auto_dt "$p" "$q")" -v b="$dt_7_14" 'BEGIN{printf "%.17g", a < b ? a : b}')
  : > "$work/pairs"
  for _ in $(seq "$reps"); do echo "$(rate "$p" "$q" "$dt") $(rate 7 14 "$dt")" >> "$work/pairs"; done
  printf '%-8s %12.3g %12.3g %8.2f\n' "($p,$q)" "$(awk '{print $1}' "$work/pairs" | median)" \
    "$(awk '{print $2}' "$work/pairs" | median)" "$(awk '{printf "%.4f\n", $1 / $2}' "$work/pairs" | median)"
done
