#!/usr/bin/env bash
# Cost against size. The bonded (7,14) slit plate (cases/slit_plate_rect_7_14.toml) from 42k to 4.2M particles
# and the 3-D block (cases/block3d_slit.toml) from 55k to 3.5M, the same bodies at finer r0, dt scaled with r0
# (5e-7 s/cm x r0: a third of the stability limit), quiet steps only (every run ends long before the first
# broken bond). For each size: particle-steps/s on all cores and on one (of the steps alone: see steps_rate),
# the thread count the engine chose, the wall time per particle-step, peak resident memory per particle
# (/usr/bin/time), and the setup before the first frame (run.json setup_s). Then pmfrag against LAMMPS (Debian's lmp, 2 threads against 2 ranks) on the 3-D block at
# 439,520 particles, alternated pairs. Writes gallery/scale.csv and its charts (gallery/scale_cost.png,
# gallery/scale_memory.png).
#   bash bench/scale.sh              # ~15 min on 2 cores (AMD EPYC Zen 5, 2026-12-04), ~2.5 GB of memory at the largest size
#   QUICK=1 bash bench/scale.sh      # sizes up to ~700k only, output in build/bench-scale (not gallery/)
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/lib.sh
bash scripts/install-deps bench > /dev/null
bash scripts/build > /dev/null
pmfrag=$PWD/build/app/pmfrag
work=$PWD/build/bench-scale
mkdir -p "$work"
quick=${QUICK:-0}
csv=gallery/scale.csv
[ "$quick" = 1 ] && csv=$work/scale.csv
pin_1=(taskset -c "$(($(nproc) - 1))")
proc=$(processor)
today=$(date -u +%F)

# One run, frames at the start and the end only, positions only. Prints "rate threads_used setup_s rss_kb particles",
# rate being the steps' own: particles x steps / (wall_s - output_s), the first frame and the closing checkpoint
# (hundreds of MB at millions of particles) left out; the thread tuner's probes stay in, as they are the engine's.
steps_rate() {  # steps_rate SCENE THREADS STEPS DT SET...
  local scene=$1 threads=$2 steps=$3 dt=$4 pin=()
  shift 4
  [ "$threads" = 1 ] && pin=("${pin_1[@]}")
  local end
  end=$(awk "BEGIN{printf \"%.10g\", $steps * $dt}")
  /usr/bin/time -f "%M" -o "$work/rss.txt" "${pin[@]}" "$pmfrag" run "$scene" --out "$work/run" --force -q \
    --threads "$threads" --set "time.dt=$dt" --set "time.end=$end" --set "output.every=$end" \
    --set 'output.fields=["position"]' "$@" > /dev/null
  /usr/bin/python3 - "$work/run/run.json" "$(cat "$work/rss.txt")" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
used = max(r["steps_by_threads"].items(), key=lambda kv: kv[1])[0]
rate = r["particles"] * r["steps"] / (r["wall_s"] - r["output_s"])
print(f'{rate:.4g} {used} {r["setup_s"]:.3g} {sys.argv[2]} {r["particles"]}')
PY
}

echo "machine: $proc, $(nproc) cores, L2 $(($(getconf LEVEL2_CACHE_SIZE 2>/dev/null || echo 0) / 1024)) KiB per core; $today"
echo "dim,particles,r0_cm,steps,particle_steps_per_s,ns_per_particle_step,threads_used,one_thread_particle_steps_per_s,speedup_over_one_thread,peak_rss_bytes_per_particle,setup_s,setup_s_per_million,processor,date" > "$csv.tmp"
printf "%-4s %10s %9s %7s %12s %8s %8s %12s %8s %9s %8s %9s\n" dim particles r0 steps "p-steps/s" "ns/p-s" threads \
  "1 thread" "speedup" "RSS B/p" "setup s" "s/million"
measure() {  # measure DIM R0 SCENE BUDGET ESTIMATED_PARTICLES SET...
  local dim=$1 r0=$2 scene=$3 budget=$4 n=$5
  shift 5
  local dt steps all one rate used setup rss rate1
  dt=$(awk "BEGIN{printf \"%.4g\", 5e-7 * $r0}")
  steps=$(awk "BEGIN{s = int($budget / $n); print (s < 100) ? 100 : s}")
  all=$(steps_rate "$scene" "$(nproc)" "$steps" "$dt" --set "body.0.r0=$r0" "$@")
  one=$(steps_rate "$scene" 1 "$steps" "$dt" --set "body.0.r0=$r0" "$@")
  read -r rate used setup rss n <<< "$all"
  rate1=$(echo "$one" | awk '{print $1}')
  awk -v d="$dim" -v n="$n" -v r0="$r0" -v s="$steps" -v rate="$rate" -v used="$used" -v rate1="$rate1" \
    -v rss="$rss" -v setup="$setup" -v proc="$proc" -v day="$today" -v csv="$csv.tmp" 'BEGIN {
      ns = 1e9 / rate; bpp = rss * 1024 / n; spm = setup / (n / 1e6)
      printf "%-4s %10d %9s %7d %12.4g %8.3g %8s %12.4g %7.2fx %9.0f %8.3g %9.3g\n", d, n, r0, s, rate, ns, used, rate1, rate / rate1, bpp, setup, spm
      printf "%s,%d,%s,%d,%.4g,%.4g,%s,%.4g,%.3f,%.0f,%.4g,%.4g,\"%s\",%s\n", d, n, r0, s, rate, ns, used, rate1, rate / rate1, bpp, setup, spm, proc, day >> csv
    }'
}

plate=cases/slit_plate_rect_7_14.toml
block=cases/block3d_slit.toml
r0s_2d="0.05 0.025 0.0125 0.00625 0.005"
blocks_3d="0.2:41,67,20 0.1:82,134,40 0.0666666667:123,201,60 0.05:164,268,80"
if [ "$quick" = 1 ]; then r0s_2d="0.05 0.025 0.0125"; blocks_3d="0.2:41,67,20 0.1:82,134,40"; fi
# The step count from the particle count the spacing gives (2,673 at r0 = 0.2 cm; sites multiplied in 3-D).
for r0 in $r0s_2d; do measure 2 "$r0" "$plate" 2e9 "$(awk "BEGIN{print int(2673 * (0.2 / $r0)^2)}")"; done
for b in $blocks_3d; do
  sites=${b#*:}
  measure 3 "${b%%:*}" "$block" 8e8 "$(echo "$sites" | awk -F, '{print $1 * $2 * $3}')" --set "body.0.sites=[$sites]"
done
mv "$csv.tmp" "$csv"

# pmfrag against LAMMPS on the 439,520-particle block, bonded, 2 threads against 2 ranks, alternated pairs;
# LAMMPS' "Loop time" over STEPS steps against pmfrag's steps alone (see steps_rate), both without setup.
reps=${REPS:-3}
steps=${LAMMPS_STEPS:-1000}
dt=5e-8
lammps_deck "$pmfrag" "$block" "$steps" "$work/lmp" --set 'body.0.sites=[82,134,40]' --set body.0.r0=0.1 \
  --set "time.dt=$dt" > /dev/null
: > "$work/ratios"; : > "$work/ours"; : > "$work/theirs"
for _ in $(seq "$reps"); do
  a=$(steps_rate "$block" 2 "$steps" "$dt" --set 'body.0.sites=[82,134,40]' --set body.0.r0=0.1 | awk '{print $1}')
  b=$(cd "$work/lmp" && mpirun --allow-run-as-root --oversubscribe -np 2 lmp -in in.lammps -log none | grep "Loop time" |
    awk '{printf "%.4g\n", $12 * $9 / $4}')
  echo "$a" >> "$work/ours"; echo "$b" >> "$work/theirs"; awk "BEGIN{print $a / $b}" >> "$work/ratios"
done
echo "3-D block, 439,520 particles, bonded, $steps steps, 2 threads against 2 LAMMPS ranks:" \
  "pmfrag $(median < "$work/ours"), LAMMPS $(median < "$work/theirs") particle-steps/s," \
  "$(median < "$work/ratios" | awk '{printf "%.1fx", $1}') (median of $reps pairs: $(sort -g "$work/ratios" | awk '{printf "%s%.1f", (NR > 1 ? "/" : ""), $1}'))"

"$pmfrag" study scale-figures "$csv"
