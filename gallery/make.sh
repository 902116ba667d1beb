#!/usr/bin/env bash
# Regenerates the committed gallery images from scratch (about twelve minutes on 2 cores with AVX-512; the 3-D
# sphere and blocks are most of it):
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
"$pmfrag" run cases/disc_wall_impact.toml --out "$work/disc_wall_impact" --force -q --set output.every=1e-5 > /dev/null
"$pmfrag" render "$work/disc_wall_impact" --no-frames --field fragment_id --panel 0,0.1,0.3,1 --size 800 \
  --panel-out gallery/disc_wall_impact_fragments.png
"$pmfrag" render "$work/disc_wall_impact" --field fragment_id --size 480 --movie --fps 15 > /dev/null
cp "$work/disc_wall_impact/crack.gif" gallery/disc_wall_impact.gif
"$pmfrag" run cases/sphere_impact.toml --out "$work/sphere_impact" --force -q > /dev/null
"$pmfrag" render "$work/sphere_impact" --no-frames --field fragment_id --cut x=0 --panel 0,0.1,0.2,0.4 --size 1000 \
  --panel-out gallery/sphere_impact_fragments_cut.png
# The 3-D block: 54,940 particles to 1.7e-2 s (cracks from the slit tips), and 439,520 particles (r0 = 0.1 cm)
# to 2e-3 s, before any bond breaks (a minute and three and a half minutes on 2 cores with AVX-512).
"$pmfrag" run cases/block3d_slit.toml --out "$work/block3d" --force -q --set time.end=5e-4 > /dev/null
"$pmfrag" render "$work/block3d" --field displacement --no-frames --cut z=1.2 --panel 0,1 --size 800 \
  --panel-out gallery/block3d_displacement.png
"$pmfrag" run cases/block3d_slit.toml --out "$work/block3d_long" --force -q --set time.end=1.7e-2 > /dev/null
for cut in "" z=0.0; do
  "$pmfrag" render "$work/block3d_long" --field damage --no-frames ${cut:+--cut $cut} --panel 0.7,0.76,0.85,1 \
    --size 800 --panel-out "gallery/block3d_damage${cut:+_cut}.png"
done
"$pmfrag" run cases/block3d_slit.toml --out "$work/block3d_440k" --force -q --set 'body.0.sites=[82,134,40]' \
  --set body.0.r0=0.1 --set time.dt=5e-8 --set time.end=2e-3 --set output.every=5e-4 > /dev/null
for cut in "" x=0.5; do
  "$pmfrag" render "$work/block3d_440k" --field displacement --no-frames ${cut:+--cut $cut} --panel 0,0.5,1 \
    --size 800 --panel-out "gallery/block3d_440k${cut:+_cut}.png"
done
ls -l gallery/*.png gallery/*.gif
