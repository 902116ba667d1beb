#!/usr/bin/env bash
# Runs the pmfrag program as a user would: good input gives Table 1, bad input a one-line error naming the
# argument and a non-zero exit.
set -u
pmfrag=$1
source "$(dirname "$0")/check.sh"

json=$("$pmfrag" material --pq 7,14 --json)
check "json parses and matches Table 1 (7,14)" "python3 - <<PY
import json; m = json.loads('''$json''')[0]
assert abs(m['G']/1.102e5 - 1) < 5e-4, m['G']
assert abs(m['H']/1.411 - 1) < 5e-4, m['H']
assert abs(m['E_GPa'] - 150.7062) < 5e-5, m['E_GPa']
assert m['N'] == 54940 and abs(m['mass_g'] - 0.05172) < 1e-5
assert abs(m['dt_max_stretch_s']/8.3e-7 - 1) < 0.01
PY"
check "default table lists the paper's three pairs" \
  "\"$pmfrag\" material | head -1 | grep -q '(3,5).*(5,10).*(7,14)'"
grid=$("$pmfrag" material --grid)
check "grid has a header and 105 rows" "[ \$(printf '%s\n' \"\$grid\" | wc -l) -eq 106 ] && printf '%s\n' \"\$grid\" | head -1 | grep -q '^p,q,G,H,E_GPa'"
check "--help explains options" "\"$pmfrag\" material --help | grep -q -- '--block'"
check "top-level --help lists material" "\"$pmfrag\" --help | grep -q material"

bad() {  # bad NAME EXPECTED_WORD ARGS...
  local name=$1 word=$2; shift 2
  local err rc
  err=$("$pmfrag" "$@" 2>&1 >/dev/null); rc=$?
  if [ $rc -eq 0 ]; then echo "FAIL: $name exited 0"; fail=1; return; fi
  if [ "$(printf '%s\n' "$err" | wc -l)" -ne 1 ]; then echo "FAIL: $name: not one line: $err"; fail=1; return; fi
  if ! printf '%s' "$err" | grep -q -- "$word"; then echo "FAIL: $name: '$err' does not name $word"; fail=1; return; fi
  echo "ok: $name -> $err"
}
bad "q <= p" --pq material --pq 7,7
bad "p < 1" --pq material --pq 0,5
bad "q > 64, as run refuses it" "at most 64" material --pq 400,800 --json
bad "r0 <= 0" --r0 material --r0 0
bad "negative r0" --r0 material --r0 -0.2
bad "malformed pq" --pq material --pq 7,x
bad "malformed r0" --r0 material --r0 abc
bad "malformed block" --block material --block 8,11
bad "unknown option" --frobnicate material --frobnicate
bad "no subcommand" subcommand

# A run whose adaptive step would fall below 1e-6 of its cap stops at once, keeps a checkpoint, and what reads
# the trajectory says it is partial (here forced by a safety factor of 1e-8).
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
bad "adaptive step collapsed" "collapsed" run "$src/cases/impact.toml" --out "$work/c" -q --set time.safety=1e-8 \
  --set time.dt_max=1e-7 --set time.end=1e-5
check "the collapsed run keeps a checkpoint and says it did not complete" \
  "[ -f '$work/c/checkpoint.h5' ] && grep -q '\"completed\": false' '$work/c/run.json'"
check "fragments of the collapsed run say PARTIAL" "\"$pmfrag\" fragments '$work/c' | grep -q 'PARTIAL' && grep -q '\"partial\": true' '$work/c/summary.json'"
rm -rf "$work"
exit $fail
