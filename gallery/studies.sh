#!/usr/bin/env bash
# The long studies behind the gallery's study figures (not part of CI):
#   bash gallery/studies.sh accuracy   # dt and r0 against wall time: ~4 min on 2 cores
#   bash gallery/studies.sh sweep      # the slit plate over all 105 (p,q): ~25 min on 2 cores
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build > /dev/null
pmfrag=build/app/pmfrag
case "${1:-}" in
  accuracy)
    "$pmfrag" study accuracy cases/slit_plate_rect_7_14.toml --out out/accuracy --set time.end=1.6e-2 \
      --png gallery/accuracy_pareto.png
    cp out/accuracy/accuracy.csv gallery/accuracy.csv
    ;;
  sweep)
    start=$(date +%s)
    "$pmfrag" sweep cases/sweep_pq.toml --out out/sweep_pq
    echo "sweep wall time: $(( $(date +%s) - start )) s"
    cp out/sweep_pq/sweep.csv gallery/sweep_pq.csv
    ;;
  *) echo "usage: gallery/studies.sh accuracy|sweep" >&2; exit 2 ;;
esac
