#!/usr/bin/env bash
# Post-processing cost: `pmfrag fragments` and `pmfrag export` on the whole (7,14) slit plate (151 frames) and
# on the 3-D block (54,940 particles, 110 frames), wall time and peak memory of each, for each VTU compressor.
# With SCALE=1, also `fragments`, `export` and `render` on a 2,704,416-particle plate and a 3,516,160-particle
# block of 5 frames each, per million particles per frame (the runs take ~1 and ~2 minutes, 1.4 and 3 GB).
# The runs are made once and kept in build/bench-post (the 54,940-particle block takes ~5 min).
#   [SCALE=1] bench/postprocess.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
source bench/lib.sh
build=${1:-build}
pmfrag=$build/app/pmfrag
work=$build/bench-post
mkdir -p "$work"
[ -f "$work/plate/run.json" ] || "$pmfrag" run cases/slit_plate_7_14.toml --out "$work/plate" --force -q
[ -f "$work/block/run.json" ] || "$pmfrag" run cases/block3d_slit.toml --out "$work/block" --force -q \
  --set output.every=1.2e-4
measure() {  # label command... -> sets wall (s) and rss (KB)
  local label=$1; shift
  /usr/bin/time -f "%e %M" -o "$work/time.txt" "$@" > /dev/null
  read -r wall rss < "$work/time.txt"
  printf '| %s | %.2f | %.0f |\n' "$label" "$wall" "$((rss / 1024))"
}
frames_of() { /usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1])['particles/all/position/value'].shape[0])" "$1/trajectory.h5"; }
echo "processor: $(processor), $(nproc) cores"
echo "| step | wall (s) | peak memory (MB) |"
echo "|---|---|---|"
for scene in plate block; do
  measure "$scene ($(frames_of "$work/$scene") frames): fragments" "$pmfrag" fragments "$work/$scene"
  for c in lz4 zlib; do
    rm -rf "$work/$scene/vtk"
    measure "$scene: export --compress $c" "$pmfrag" export "$work/$scene" --compress "$c"
    echo "|   (VTU on disk: $(du -sh "$work/$scene/vtk" | cut -f1)) | | |"
  done
done
[ "${SCALE:-0}" = 1 ] || exit 0

# Millions of particles, a few frames: dt scaled with r0 so that the steps are those of a stable run.
[ -f "$work/plate-2.7M/run.json" ] || "$pmfrag" run cases/slit_plate_rect_7_14.toml --out "$work/plate-2.7M" --force -q \
  --set body.0.r0=0.00625 --set time.dt=3e-9 --set time.end=6e-8 --set output.every=1.5e-8
[ -f "$work/block-3.5M/run.json" ] || "$pmfrag" run cases/block3d_slit.toml --out "$work/block-3.5M" --force -q \
  --set 'body.0.sites=[164,268,80]' --set body.0.r0=0.05 --set time.dt=2.5e-8 --set time.end=5e-7 --set output.every=1.25e-7
echo
echo "| step | wall (s) | peak memory (MB) | s per million particles per frame | peak bytes per particle |"
echo "|---|---|---|---|---|"
for scene in plate-2.7M block-3.5M; do
  n=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1])['particles/all/position/value'].shape[1])" "$work/$scene/trajectory.h5")
  frames=$(frames_of "$work/$scene")
  for step in fragments export render; do
    rm -rf "$work/$scene/vtk"
    /usr/bin/time -f "%e %M" -o "$work/time.txt" "$pmfrag" "$step" "$work/$scene" > /dev/null
    read -r wall rss < "$work/time.txt"
    awk -v l="$scene ($n particles, $frames frames): $step" -v w="$wall" -v r="$rss" -v n="$n" -v f="$frames" \
      'BEGIN { printf "| %s | %.2f | %.0f | %.2f | %.0f |\n", l, w, r / 1024, w / (n / 1e6) / f, r * 1024 / n }'
  done
done
