#!/usr/bin/env bash
# The long studies behind the gallery's study figures (not part of CI):
#   bash gallery/studies.sh accuracy   # dt, float precision and r0 against wall time: ~6 min on 2 cores
#   bash gallery/studies.sh sweep      # the slit plate over all 105 (p,q): ~25 min on 2 cores
#   bash gallery/studies.sh figures    # the paper's Figs. 3, 7, 8, 10, 11 from the material model: 2 s
#   bash gallery/studies.sh impact     # the disc against a fixed wall, 8 speeds x 3 laws, and its charts
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build > /dev/null
pmfrag=build/app/pmfrag
case "${1:-}" in
  accuracy)
    "$pmfrag" study accuracy cases/slit_plate_rect_7_14.toml --out out/accuracy --set time.end=1.6e-2 \
      --knobs dt,r0,precision --png gallery/accuracy_pareto.png
    cp out/accuracy/accuracy.csv gallery/accuracy.csv
    ;;
  sweep)
    start=$(date +%s)
    "$pmfrag" sweep cases/sweep_pq.toml --out out/sweep_pq
    echo "sweep wall time: $(( $(date +%s) - start )) s"
    cp out/sweep_pq/sweep.csv gallery/sweep_pq.csv
    "$pmfrag" study sweep-figures out/sweep_pq --prefix gallery/sweep_pq
    ;;
  impact)
    start=$(date +%s)
    "$pmfrag" sweep cases/sweep_impact.toml --out out/sweep_impact
    echo "sweep wall time: $(( $(date +%s) - start )) s"
    cp out/sweep_impact/sweep.csv gallery/sweep_impact.csv
    "$pmfrag" study sweep-figures out/sweep_impact --prefix gallery/sweep
    ;;
  figures)
    "$pmfrag" study figures --out gallery
    ;;
  *) echo "usage: gallery/studies.sh accuracy|sweep|figures|impact" >&2; exit 2 ;;
esac
