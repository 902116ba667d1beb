#!/usr/bin/env bash
# Faults, injected as a user would meet them (label `faults`): a full disk (ulimit -f: writes fail with
# EFBIG) for run, fragments, export, render (frames and movie) and sweep, two writers on one run folder, a
# process killed mid-stage (fragments, export, render, a sweep between cases), exponents out of range. Each must end
# with a non-zero exit and one line naming the file and the cause, and keep what was there before.
#   bash tests/faults_test.sh PMFRAG SOURCE_DIR
set -u
pmfrag=$1
src=$2
source "$(dirname "$0")/check.sh"
work=$(mktemp -d)
holder=
trap '[ -n "$holder" ] && kill -9 "$holder" 2>/dev/null; rm -rf "$work"' EXIT
plate=$src/cases/slit_plate_7_14.toml
sum() { sha256sum "$1" | cut -d' ' -f1; }

# A finished run with its fragment tables: what the faults below must not damage.
"$pmfrag" run "$plate" --out "$work/good" -q --set time.end=2e-3 > /dev/null 2>&1
"$pmfrag" fragments "$work/good" > /dev/null
before=$(sum "$work/good/summary.json")

# --- a full disk ---------------------------------------------------------------------------------------
err=$( (ulimit -f 1; "$pmfrag" fragments "$work/good") 2>&1 >/dev/null); rc=$?
check "fragments on a full disk exits non-zero" "[ $rc -ne 0 ]"
check "fragments on a full disk names the file and the cause in one line" \
  "[ \$(printf '%s\n' \"\$err\" | wc -l) -eq 1 ] && printf '%s' \"\$err\" | grep -q 'fragments_timeline.csv: cannot write: File too large'"
check "fragments on a full disk leaves the previous summary.json as it was" "[ \"\$(sum $work/good/summary.json)\" = $before ]"

err=$( (ulimit -f 8; "$pmfrag" export "$work/good") 2>&1 >/dev/null); rc=$?
check "export on a full disk exits non-zero, naming the file and the cause" \
  "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'vtk/frame_00000.vtu: cannot write: File too large'"

err=$( (ulimit -f 1500; "$pmfrag" run "$plate" --out "$work/full" -q --set time.end=3e-2) 2>&1 >/dev/null); rc=$?
check "run on a full disk exits 1 (no crash on the way out)" "[ $rc -eq 1 ]"
check "run on a full disk says so in one line, without HDF5's stack, with the frames and checkpoint kept" \
  "[ \$(printf '%s\n' \"\$err\" | wc -l) -eq 1 ] && printf '%s' \"\$err\" | grep -q 'trajectory.h5: cannot write: File too large (frames 0\.\.[0-9]*, to t = .* s, are whole; the checkpoint at frame [0-9]*, t = .* s, is intact)'"
check "the frames written before the disk filled are read" \
  "\"$pmfrag\" fragments \"$work/full\" | grep -q 'frames lie before the cut'"

# render: the new frames go to frames.part/, so a failed render keeps the previous frames and leaves no partial ones.
"$pmfrag" render "$work/good" --every 10 > /dev/null
frame0=$(sum "$work/good/frames/frame_00000.png")
err=$( (ulimit -f 20; "$pmfrag" render "$work/good" --every 5) 2>&1 >/dev/null); rc=$?
check "render on a full disk exits non-zero, naming the frame and the cause" \
  "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'frame_00000.png: cannot write: File too large'"
check "render on a full disk keeps the previous frames, whole, and none of the new ones" \
  "[ \"\$(sum $work/good/frames/frame_00000.png)\" = $frame0 ] && [ ! -e $work/good/frames/frame_00005.png ] && [ ! -e $work/good/frames.part ]"
if command -v ffmpeg > /dev/null; then
  "$pmfrag" render "$work/good" --every 10 --size 256 --movie > /dev/null
  movie=$(sum "$work/good/crack.mp4")
  err=$( (ulimit -f 200; "$pmfrag" render "$work/good" --every 1 --size 512 --movie) 2>&1 >/dev/null); rc=$?
  check "a movie on a full disk exits non-zero, naming crack.mp4 and ffmpeg's reason" \
    "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'crack.mp4: cannot write: ffmpeg: .*File too large'"
  check "and keeps the previous movie" "[ \"\$(sum $work/good/crack.mp4)\" = $movie ]"
else
  echo "skip: the movie on a full disk (no ffmpeg)"
fi

# sweep: a case that cannot write fails alone, the sweep exits 1, the finished cases are untouched.
sweep_spec=$src/cases/sweep_pq.toml
sweep_args=(--jobs 1 --set time.end=4e-3)
"$pmfrag" sweep "$sweep_spec" --out "$work/sweep" --pairs 7,14 5,10 "${sweep_args[@]}" > /dev/null 2>&1
case_sum=$(sum "$work/sweep/p7_q14/summary.json")
out=$( (ulimit -f 100; "$pmfrag" sweep "$sweep_spec" --out "$work/sweep" --pairs 7,14 5,10 1,2 "${sweep_args[@]}") 2>&1); rc=$?
check "sweep on a full disk exits 1 and says which cases failed" "[ $rc -eq 1 ] && printf '%s' \"\$out\" | grep -q '1 of 3 cases failed'"
check "the failed case's row in sweep.csv names the file and the cause" \
  "grep -q '^p1_q2,.*trajectory.h5.part: cannot write: File too large' $work/sweep/sweep.csv"
check "the finished cases are untouched" "[ \"\$(sum $work/sweep/p7_q14/summary.json)\" = $case_sum ]"

# --resume after the full disk: the cut trajectory is rebuilt from the frames the checkpoint counts, and the run
# ends with the frames of an uninterrupted one, bitwise.
"$pmfrag" run --resume "$work/full" -q > /dev/null 2>&1; rc=$?
"$pmfrag" run "$plate" --out "$work/full_whole" -q --set time.end=3e-2 > /dev/null 2>&1
check "--resume after a full disk completes, bitwise the uninterrupted run" \
  "[ $rc -eq 0 ] && /usr/bin/python3 - $work/full/trajectory.h5 $work/full_whole/trajectory.h5 <<'PY'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
keys = ['particles/all/position/value', 'particles/all/velocity/value', 'particles/all/position/step',
        'observables/total_energy/value', 'connectivity/broken_bonds/bond', 'connectivity/broken_bonds/rows_at_frame/value']
sys.exit(0 if all(a[k].shape == b[k].shape and np.array_equal(a[k][()], b[k][()]) for k in keys) else 1)
PY"

# --- two writers -----------------------------------------------------------------------------------------
"$pmfrag" run "$plate" --out "$work/busy" -q --set time.end=1 > /dev/null 2>&1 &
holder=$!
for _ in $(seq 100); do grep -q "pid $holder" "$work/busy/.pmfrag.lock" 2>/dev/null && break; sleep 0.1; done
check "a running run names itself in the folder's lock" "grep -q \"pid $holder: .*pmfrag run\" \"$work/busy/.pmfrag.lock\""
for second in "run $plate --out $work/busy -q --force" "fragments $work/busy" "export $work/busy" "render $work/busy"; do
  err=$("$pmfrag" $second 2>&1 >/dev/null); rc=$?
  check "a second writer ('pmfrag ${second%% *}') is refused at once, naming the holder" \
    "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q \"in use by another pmfrag (pid $holder: \""
done
kill -9 "$holder"
wait "$holder" 2>/dev/null
holder=
check "a killed holder leaves no stale lock: fragments runs" "\"$pmfrag\" fragments \"$work/busy\" > /dev/null"
"$pmfrag" run --resume "$work/busy" -q > /dev/null 2>&1 &
resumed=$!
for _ in $(seq 100); do grep -q "pid $resumed" "$work/busy/.pmfrag.lock" 2>/dev/null && break; sleep 0.1; done
check "and --resume takes the folder over" "grep -q \"pid $resumed: .*--resume\" \"$work/busy/.pmfrag.lock\""
kill -9 "$resumed" 2>/dev/null
wait "$resumed" 2>/dev/null

# --- a stage killed midway ------------------------------------------------------------------------------
cp -r "$work/good" "$work/killed"
rm -f "$work/killed"/fragment* "$work/killed/summary.json"
"$pmfrag" fragments "$work/killed" > /dev/null &
k=$!
sleep 0.05
kill -9 "$k" 2>/dev/null
wait "$k" 2>/dev/null
whole=1
for f in "$work/killed"/fragment*.csv "$work/killed/summary.json"; do
  [ -e "$f" ] || continue
  [ -s "$f" ] || whole=0
done
[ ! -e "$work/killed/summary.json" ] || /usr/bin/python3 -c "import json,sys; json.load(open(sys.argv[1]))" "$work/killed/summary.json" || whole=0
check "a killed fragments leaves each table whole or absent" "[ $whole -eq 1 ]"
"$pmfrag" fragments "$work/killed" > /dev/null
check "fragments run again after a kill writes what an uninterrupted run wrote" \
  "[ \"\$(sum $work/killed/summary.json)\" = $before ] && cmp -s \"$work/killed/fragments_final.csv\" \"$work/good/fragments_final.csv\""

# export and render killed midway: running the same command again writes what an uninterrupted one wrote.
cp -r "$work/good" "$work/whole"
rm -rf "$work/whole"/frames "$work/whole"/vtk "$work/whole"/particles.pvd "$work/whole"/crack.*
"$pmfrag" export "$work/whole" > /dev/null
"$pmfrag" render "$work/whole" --every 3 > /dev/null
for stage in "export" "render --every 3"; do
  cp -r "$work/good" "$work/k_${stage%% *}"
  d=$work/k_${stage%% *}
  rm -rf "$d"/frames "$d"/vtk "$d"/particles.pvd
  "$pmfrag" $stage "$d" > /dev/null 2>&1 &
  k=$!
  sleep 0.4
  kill -9 "$k" 2>/dev/null
  wait "$k" 2>/dev/null
  "$pmfrag" $stage "$d" > /dev/null
done
check "export killed, then run again, equals an uninterrupted export" \
  "diff -r $work/whole/vtk $work/k_export/vtk > /dev/null && cmp -s $work/whole/particles.pvd $work/k_export/particles.pvd"
check "render killed, then run again, equals an uninterrupted render" \
  "diff -r $work/whole/frames $work/k_render/frames > /dev/null && [ ! -e $work/k_render/frames.part ]"

# A sweep killed between cases: its workers die with it (no orphan writes on), and the same command finishes the
# sweep with the numbers of an uninterrupted one (the timing columns aside).
"$pmfrag" sweep "$sweep_spec" --out "$work/sweep_whole" --pairs 7,14 5,10 3,5 "${sweep_args[@]}" > /dev/null 2>&1
"$pmfrag" sweep "$sweep_spec" --out "$work/sweep_killed" --pairs 7,14 5,10 3,5 "${sweep_args[@]}" > /dev/null 2>&1 &
k=$!
for _ in $(seq 400); do [ -e "$work/sweep_killed/p7_q14/summary.json" ] && break; sleep 0.05; done
kill -9 "$k"
wait "$k" 2>/dev/null
orphans=0
for _ in $(seq 50); do
  pgrep -f "pmfrag run .*$work/sweep_killed" > /dev/null || { orphans=0; break; }
  orphans=1
  sleep 0.1
done
check "a killed sweep's workers stop with it" "[ $orphans -eq 0 ]"
"$pmfrag" sweep "$sweep_spec" --out "$work/sweep_killed" --pairs 7,14 5,10 3,5 "${sweep_args[@]}" > /dev/null 2>&1
check "the sweep run again after a kill completes with the uninterrupted sweep's results" \
  "/usr/bin/python3 - $work/sweep_whole/sweep.csv $work/sweep_killed/sweep.csv <<'PY'
import csv, sys
def rows(path):
    return [{k: v for k, v in r.items() if k not in ('particle_steps_per_s', 'wall_s')} for r in csv.DictReader(open(path))]
a, b = rows(sys.argv[1]), rows(sys.argv[2])
sys.exit(0 if a == b and len(a) == 3 and all(r['status'] == 'completed' for r in a) else 1)
PY"

# --- a read-only folder, a file where a folder should be ----------------------------------------------
# Root writes anywhere, so as root the read-only checks run as the user nobody (setpriv), with the binary and
# the run copied to a folder that user can reach.
as_user=()
[ "$(id -u)" -eq 0 ] && as_user=(setpriv --reuid=65534 --regid=65534 --clear-groups)
pub=$(mktemp -d /tmp/pmfrag-faults.XXXXXX)
trap '[ -n "$holder" ] && kill -9 "$holder" 2>/dev/null; rm -rf "$work" "$pub"' EXIT
chmod 755 "$pub"
cp "$pmfrag" "$plate" "$pub/"
cp -r "$work/good" "$pub/ro"
chmod -R a+rX "$pub/ro"
chmod a-w "$pub/ro"
ro_before=$(cd "$pub/ro" && sha256sum summary.json trajectory.h5)
for stage in fragments export render; do
  err=$("${as_user[@]}" "$pub/pmfrag" $stage "$pub/ro" 2>&1 >/dev/null); rc=$?
  check "$stage in a read-only folder exits non-zero in one line naming the folder and the cause" \
    "[ $rc -ne 0 ] && [ \$(printf '%s\n' \"\$err\" | wc -l) -eq 1 ] && printf '%s' \"\$err\" | grep -q '$pub/ro: cannot write in the folder: Permission denied'"
done
err=$("${as_user[@]}" "$pub/pmfrag" run "$pub/$(basename "$plate")" --out "$pub/ro/new" -q 2>&1 >/dev/null); rc=$?
check "run into a read-only folder exits non-zero, naming the folder it cannot make" \
  "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q '$pub/ro/new: cannot make the folder: Permission denied'"
check "the read-only run folder is as it was" "[ \"\$(cd $pub/ro && sha256sum summary.json trajectory.h5)\" = \"\$ro_before\" ]"

touch "$work/a_file"
err=$("$pmfrag" run "$plate" --out "$work/a_file" -q 2>&1 >/dev/null); rc=$?
check "run --out naming a file is refused in one line, and the file is left alone" \
  "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'a_file: is a file, not a folder' && [ ! -s $work/a_file ]"
cp -r "$work/good" "$work/filed"
rm -rf "$work/filed/vtk" "$work/filed/frames"
echo keep > "$work/filed/vtk"
echo keep > "$work/filed/frames"
for stage in export render; do
  err=$("$pmfrag" $stage "$work/filed" 2>&1 >/dev/null); rc=$?
  out=vtk; [ $stage = render ] && out=frames
  check "$stage where a file holds the name $out/ is refused, naming it, and keeps the file" \
    "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'filed/$out: is a file, not a folder' && [ \"\$(cat $work/filed/$out)\" = keep ]"
done

# A file that is not HDF5: one line by default; HDF5's own stack only with --verbose.
mkdir "$work/junk" && echo junk > "$work/junk/trajectory.h5"
err=$("$pmfrag" fragments "$work/junk" 2>&1 >/dev/null); rc=$?
check "a trajectory that is not HDF5 is refused in one line, naming it, without HDF5's stack" \
  "[ $rc -ne 0 ] && [ \$(printf '%s\n' \"\$err\" | wc -l) -eq 1 ] && printf '%s' \"\$err\" | grep -q 'junk/trajectory.h5: cannot open as HDF5'"
err=$("$pmfrag" fragments "$work/junk" --verbose 2>&1 >/dev/null)
check "--verbose adds HDF5's own stack" "printf '%s' \"\$err\" | grep -q 'HDF5-DIAG' && printf '%s' \"\$err\" | grep -q 'cannot open as HDF5'"

# --- values out of range ---------------------------------------------------------------------------------
for pq in 7,65 400,800; do
  err=$("$pmfrag" material --pq "$pq" --json 2>&1 >/dev/null); rc=$?
  check "material --pq $pq is refused like run refuses it" "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'at most 64'"
done

exit $fail
