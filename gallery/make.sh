#!/usr/bin/env bash
# Regenerates the committed gallery images from scratch (about a minute on 2 cores):
#   bash gallery/make.sh
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build > /dev/null
pmfrag=build/app/pmfrag
work=${PMFRAG_GALLERY_WORK:-out/gallery}
mkdir -p "$work"
for pq in 3_5 5_10 7_14; do
  "$pmfrag" run "cases/slit_plate_$pq.toml" --out "$work/slit_plate_$pq" --force -q > /dev/null
  "$pmfrag" render "$work/slit_plate_$pq" --no-frames --panel 0,0.84,0.9,1 --size 800 \
    --panel-out "gallery/slit_plate_${pq}_fragments.png"
done
"$pmfrag" render "$work/slit_plate_7_14" --no-frames --field displacement --panel 0,0.7,0.8,1 --size 800 \
  --panel-out gallery/slit_plate_7_14_displacement.png
"$pmfrag" render "$work/slit_plate_7_14" --no-frames --bonds --field damage --panel 0.71,0.73,0.75,0.8 --size 800 \
  --panel-out gallery/slit_plate_7_14_bonds.png
"$pmfrag" run cases/impact.toml --out "$work/impact" --force -q > /dev/null
"$pmfrag" render "$work/impact" --no-frames --field speed --panel 0,0.3,0.5,1 --size 800 --panel-out gallery/impact_speed.png
"$pmfrag" run cases/inclusion.toml --out "$work/inclusion" --force -q > /dev/null
"$pmfrag" render "$work/inclusion" --no-frames --field phase --panel 0,0.6,0.8,1 --size 800 \
  --panel-out gallery/inclusion_phase.png
"$pmfrag" run cases/disc_wall_impact.toml --out "$work/disc_wall_impact" --force -q > /dev/null
"$pmfrag" render "$work/disc_wall_impact" --no-frames --field fragment_id --panel 0,0.1,0.3,1 --size 800 \
  --panel-out gallery/disc_wall_impact_fragments.png
ls -l gallery/*.png
