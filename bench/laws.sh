#!/usr/bin/env bash
# Every (p,q) as fast as the paper's (7,14)? The bonded slit plate, one thread, dt "auto" (each law's own
# Eq. 15 step), 0 to 1e-3 s: each law alternates with (7,14) in REPS pairs (default 3); the ratio is the
# median of the pairs' ratios (law / (7,14), particle-steps per second).
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
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/lib.sh
rate() {  # rate P Q -> particle-steps/s
  "$bin" run cases/slit_plate_7_14.toml --out "$work/run" --force -q --threads 1 --set "phase.0.p=$1" \
    --set "phase.0.q=$2" --set 'time.dt="auto"' --set time.end=1e-3 --set output.every=1 > /dev/null
  sed -n 's/.*"particle_steps_per_s": *\([0-9.e+-]*\).*/\1/p' "$work/run/run.json"
}
echo "processor: $(processor); kernels: $( \
  "$bin" run cases/slit_plate_7_14.toml --out "$work/k" -q --set time.end=1e-6 > /dev/null 2>&1; \
  sed -n 's/.*"kernels": *"\([a-z0-9-]*\)".*/\1/p' "$work/k/run.json"); $(date -u +%F); $reps pairs a law"
printf '%-8s %12s %12s %8s\n' "(p,q)" "law" "(7,14)" ratio
for pq in "${laws[@]}"; do
  p=${pq%,*}
  q=${pq#*,}
  : > "$work/pairs"
  for _ in $(seq "$reps"); do echo "$(rate "$p" "$q") $(rate 7 14)" >> "$work/pairs"; done
  printf '%-8s %12.3g %12.3g %8.2f\n' "($p,$q)" "$(awk '{print $1}' "$work/pairs" | median)" \
    "$(awk '{print $2}' "$work/pairs" | median)" "$(awk '{printf "%.4f\n", $1 / $2}' "$work/pairs" | median)"
done
