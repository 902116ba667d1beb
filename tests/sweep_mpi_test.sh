#!/usr/bin/env bash
# pmfrag sweep under mpirun -np 2: four short cases handed out across both ranks, rank 0 writes sweep.csv
# with all four completed; a rerun under MPI skips them all.
#   sweep_mpi_test.sh PMFRAG SOURCE_DIR
set -u
pmfrag=$1 src=$2
source "$(dirname "$0")/check.sh"
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
cat > "$d/spec.toml" <<TOML
base = "$src/cases/slit_plate_7_14.toml"
pairs = [[3, 5], [5, 10], [7, 14], [6, 12]]
[set]
"time.end" = 2e-4
"output.every" = 1e-4
TOML
# As root in CI containers Open MPI needs to be told it may; two ranks on whatever cores there are.
mpi=(mpirun -np 2 --allow-run-as-root --oversubscribe --mca btl self,vader --mca btl_vader_single_copy_mechanism none)
"${mpi[@]}" "$pmfrag" sweep "$d/spec.toml" --out "$d/out" > "$d/log.txt" 2>&1
rc=$?
cat "$d/log.txt"
check "mpirun -np 2 sweep exits 0" "[ $rc -eq 0 ]"
check "announced 2 ranks" "grep -q '2 MPI ranks' $d/log.txt"
check "rank 0 ran a case" "grep -q '^\[rank 0\].* done' $d/log.txt"
check "rank 1 ran a case" "grep -q '^\[rank 1\].* done' $d/log.txt"
check "four cases done, none twice" "[ \$(grep -c ' done\$' $d/log.txt) -eq 4 ] && [ \$(grep ' done\$' $d/log.txt | awk '{print \$3}' | sort -u | wc -l) -eq 4 ]"
check "sweep.csv: header + 4 completed rows" "[ \$(wc -l < $d/out/sweep.csv) -eq 5 ] && [ \$(grep -c ',\"completed\"\$' $d/out/sweep.csv) -eq 4 ]"
"${mpi[@]}" "$pmfrag" sweep "$d/spec.toml" --out "$d/out" > "$d/log2.txt" 2>&1
check "rerun under MPI skips all four" "[ \$(grep -c 'finished before: skipped' $d/log2.txt) -eq 4 ] && ! grep -q ' done\$' $d/log2.txt"
exit $fail
