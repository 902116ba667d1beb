#!/usr/bin/env bash
# The long studies behind the gallery's study figures (not part of CI):
#   bash gallery/studies.sh accuracy   # dt, float precision and r0 against wall time: ~6 min on 2 cores
#   bash gallery/studies.sh r0         # the lattice spacing from 0.4 to 0.025 cm (to 169k particles): ~50 min
#   bash gallery/studies.sh sweep      # the slit plate over all 105 (p,q): ~25 min on 2 cores
#   bash gallery/studies.sh figures    # the paper's Figs. 3, 7, 8, 10, 11 from the material model: 2 s
#   bash gallery/studies.sh impact     # the disc against a fixed wall, 8 speeds x 3 laws, and its charts
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build > /dev/null
pmfrag=build/app/pmfrag
# sweep NAME: cases/sweep_NAME.toml into out/sweep_NAME, its sweep.csv and charts into gallery/
sweep() {
  local start
  start=$(date +%s)
  # A case that fails is recorded in sweep.csv and makes the sweep exit 1; the charts are drawn all the same.
  "$pmfrag" sweep "cases/sweep_$1.toml" --out "out/sweep_$1" || echo "some cases failed: see out/sweep_$1/sweep.csv"
  echo "sweep wall time: $(( $(date +%s) - start )) s"
  cp "out/sweep_$1/sweep.csv" "gallery/sweep_$1.csv"
  "$pmfrag" study sweep-figures "out/sweep_$1" --prefix "gallery/sweep_$1"
}
case "${1:-}" in
  accuracy)
    "$pmfrag" study accuracy cases/slit_plate_rect_7_14.toml --out out/accuracy --set time.end=1.6e-2 \
      --knobs dt,r0,precision --png gallery/accuracy_pareto.png
    cp out/accuracy/accuracy.csv gallery/accuracy.csv
    ;;
  r0)
    "$pmfrag" study accuracy cases/slit_plate_rect_7_14.toml --out out/accuracy_r0 --set time.end=1.6e-2 \
      --knobs r0 --r0 0.4,0.2,0.1,0.05,0.025
    cp out/accuracy_r0/accuracy.csv gallery/accuracy_r0.csv
    ;;
  sweep) sweep pq ;;
  impact) sweep impact ;;
  figures)
    "$pmfrag" study figures --out gallery
    ;;
  *) echo "usage: gallery/studies.sh accuracy|r0|sweep|figures|impact" >&2; exit 2 ;;
esac
