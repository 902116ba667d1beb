#!/usr/bin/env bash
# pmfrag sweep: a 4-case sweep gathers sweep.csv; a rerun skips finished cases; a case that fails (a step
# above its own stability limit) is recorded with its error while the others complete, and the sweep exits 1.
set -u
pmfrag=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
"$pmfrag" sweep "$src/cases/sweep_pq.toml" --out "$work/s" --pairs 3,5 5,10 7,14 1,2 --set time.end=1e-3 > "$work/out1" 2>&1 \
  || { cat "$work/out1"; echo "FAIL: sweep"; fail=1; }
rows=$(($(wc -l < "$work/s/sweep.csv") - 1))
[ "$rows" -eq 4 ] || { echo "FAIL: $rows rows in sweep.csv, expected 4"; fail=1; }
grep -q '^p7_q14,7,14,150.706,' "$work/s/sweep.csv" || { echo "FAIL: (7,14) row lacks Table 1's E"; fail=1; }
[ "$(grep -c '"completed"' "$work/s/sweep.csv")" -eq 4 ] || { echo "FAIL: not all completed"; fail=1; }
"$pmfrag" sweep "$src/cases/sweep_pq.toml" --out "$work/s" --pairs 3,5 5,10 7,14 1,2 --set time.end=1e-3 > "$work/out2" 2>&1
[ "$(grep -c 'skipped' "$work/out2")" -eq 4 ] || { cat "$work/out2"; echo "FAIL: rerun did not skip the finished cases"; fail=1; }
# dt = 1e-6 s: stable for (1,2) (limit 2.3e-6 s), refused for (7,14) (limit 3.4e-7 s).
# The sweep goes on past the failed case, then exits 1 saying how many failed.
"$pmfrag" sweep "$src/cases/sweep_pq.toml" --out "$work/f" --pairs 1,2 7,14 --set time.end=1e-4 --set time.dt=1e-6 \
  > "$work/out3" 2>&1
rc=$?
[ $rc -eq 1 ] && grep -q '1 of 2 cases failed' "$work/out3" || { cat "$work/out3"; echo "FAIL: a sweep with a failed case should exit 1 and say so (rc $rc)"; fail=1; }
grep -q '^p1_q2,.*"completed"' "$work/f/sweep.csv" || { echo "FAIL: (1,2) should complete"; fail=1; }
grep -q '^p7_q14,.*exceeds the stability limit' "$work/f/sweep.csv" || { cat "$work/f/sweep.csv"; echo "FAIL: (7,14) error not recorded"; fail=1; }
# A varied key (the impact speed) gets a column of its own after (p,q), its values quoted; the pieces and the
# mass exponent follow; sweep-figures draws the impact charts from it.
cat > "$work/impact.toml" <<EOF
base = "$src/cases/disc_wall_impact.toml"
pairs = [[7, 14]]
[set]
"time.end" = 2e-5
"output.every" = 1e-5
[vary]
"impactor.0.velocity" = [[0.0, -50000.0], [0.0, -100000.0]]
EOF
"$pmfrag" sweep "$work/impact.toml" --out "$work/i" > "$work/out4" 2>&1 || { cat "$work/out4"; echo "FAIL: impact sweep"; fail=1; }
head -1 "$work/i/sweep.csv" | grep -q '^case,p,q,impactor.0.velocity,E_GPa,.*,tau,tau_ci_low,tau_ci_high,tau_fragments_fitted,tau_m_min_g,.*,status$' \
  || { head -1 "$work/i/sweep.csv"; echo "FAIL: impact sweep.csv header"; fail=1; }
[ "$(grep -c '^p7_q14_.*,7,14,"\[ 0.0, -[0-9]*.0 \]",150.706,.*"completed"$' "$work/i/sweep.csv")" -eq 2 ] \
  || { cat "$work/i/sweep.csv"; echo "FAIL: impact sweep.csv rows"; fail=1; }
"$pmfrag" study sweep-figures "$work/i" > "$work/out5" 2>&1 && [ -s "$work/i/sweep_pieces.png" ] && [ -s "$work/i/sweep_largest.png" ] \
  || { cat "$work/out5"; echo "FAIL: impact sweep charts"; fail=1; }
[ $fail -eq 0 ] && echo "sweep: csv, skip on rerun, failure recording, varied keys and their charts work"
exit $fail
