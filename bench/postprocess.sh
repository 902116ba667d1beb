#!/usr/bin/env bash
# Post-processing cost (issue 4's targets): `pmfrag fragments` and `pmfrag export` on the whole (7,14) slit
# plate (151 frames) and on the 3-D block (54,940 particles, 110 frames), wall time and peak memory of each,
# for each VTU compressor. The runs are made once and kept in build/bench-post (the block takes ~5 min).
#   bench/postprocess.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
pmfrag=$build/app/pmfrag
work=$build/bench-post
mkdir -p "$work"
[ -f "$work/plate/run.json" ] || "$pmfrag" run cases/slit_plate_7_14.toml --out "$work/plate" --force -q
[ -f "$work/block/run.json" ] || "$pmfrag" run cases/block3d_slit.toml --out "$work/block" --force -q \
  --set output.every=1.2e-4
measure() {  # label command...
  local label=$1; shift
  /usr/bin/time -f "%e %M" -o "$work/time.txt" "$@" > /dev/null
  read -r wall rss < "$work/time.txt"
  printf '| %s | %s | %.2f | %.0f |\n' "$label" "$(nproc) cores" "$wall" "$((rss / 1024))"
}
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores"
echo "| step | machine | wall (s) | peak memory (MB) |"
echo "|---|---|---|---|"
for scene in plate block; do
  frames=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1])['particles/all/position/value'].shape[0])" "$work/$scene/trajectory.h5")
  measure "$scene ($frames frames): fragments" "$pmfrag" fragments "$work/$scene"
  for c in lz4 zlib; do
    rm -rf "$work/$scene/vtk"
    measure "$scene: export --compress $c" "$pmfrag" export "$work/$scene" --compress "$c"
    echo "|   (VTU on disk: $(du -sh "$work/$scene/vtk" | cut -f1)) | | | |"
  done
done
