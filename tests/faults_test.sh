#!/usr/bin/env bash
# Faults, injected as a user would meet them (label `faults`): a full disk (ulimit -f: writes fail with
# EFBIG), two writers on one run folder, a process killed mid-stage, exponents out of range. Each must end
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
check "run on a full disk says so in one line, without HDF5's stack" \
  "[ \$(printf '%s\n' \"\$err\" | wc -l) -eq 1 ] && printf '%s' \"\$err\" | grep -q 'trajectory.h5: cannot write: File too large'"
check "the frames written before the disk filled are read" \
  "\"$pmfrag\" fragments \"$work/full\" | grep -q 'frames lie before the cut'"

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

# --- a read-only folder ---------------------------------------------------------------------------------
if [ "$(id -u)" -ne 0 ]; then
  cp -r "$work/good" "$work/ro"
  chmod a-w "$work/ro"
  err=$("$pmfrag" fragments "$work/ro" 2>&1 >/dev/null); rc=$?
  check "fragments in a read-only folder exits non-zero, naming the path and the cause" \
    "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'Permission denied'"
  chmod u+w "$work/ro"
else
  echo "skip: a read-only folder (root writes anywhere; run this test as a user to check it)"
fi

# --- values out of range ---------------------------------------------------------------------------------
for pq in 7,65 400,800; do
  err=$("$pmfrag" material --pq "$pq" --json 2>&1 >/dev/null); rc=$?
  check "material --pq $pq is refused like run refuses it" "[ $rc -ne 0 ] && printf '%s' \"\$err\" | grep -q 'at most 64'"
done

exit $fail
