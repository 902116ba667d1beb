# Sourced by the bench scripts.
# median: the median of the numbers on stdin, one per line.
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
# processor: the model name, as the operating system reports it, with its family and model (a VM's model name
# may be as bare as "AMD EPYC", which covers Zen 3 to Zen 5).
processor() {
  local name family model
  name=$(lscpu | sed -n 's/^Model name: *//p' | head -1)
  family=$(lscpu | sed -n 's/^CPU family: *//p' | head -1)
  model=$(lscpu | sed -n 's/^Model: *//p' | head -1)
  echo "$name${family:+ (CPU family $family, model $model)}"
}
# lammps_deck PMFRAG SCENE STEPS DIR SET...: `pmfrag lammps` writes DIR/in.lammps (and its data and table) for
# STEPS steps at the scene's own time step, with a frame only at the start (the throughput runs compare steps,
# not output). Prints the time step [s].
lammps_deck() {
  local pmfrag=$1 scene=$2 steps=$3 dir=$4 dt
  shift 4
  "$pmfrag" lammps "$scene" --out "$dir" --force "$@" > /dev/null
  dt=$(awk '$1 == "timestep" {print $2}' "$dir/in.lammps")
  "$pmfrag" lammps "$scene" --out "$dir" --force "$@" --set "time.end=$(awk "BEGIN{printf \"%.17g\", $steps * $dt}")" \
    --set output.every=1 > /dev/null
  grep -q "^run $steps\$" "$dir/in.lammps" || { echo "lammps_deck: $dir/in.lammps does not run $steps steps" >&2; return 1; }
  echo "$dt"
}
# lammps_tight_skin DIR: DIR/in_tight.lammps, the deck with the skin pmfrag's cutoff model starts from (3/4 of
# the gap between D and the next lattice shell at sqrt(3) r0, which both lattices have): fewer pairs per step,
# more rebuilds. The benches give LAMMPS its faster skin.
lammps_tight_skin() {
  local dir=$1 r0 d
  r0=$(sed -n 's/.* r0 = \([0-9.e+-]*\) cm.*/\1/p' "$dir/in.lammps" | head -1)
  d=$(sed -n 's/.* D = \([0-9.e+-]*\) cm.*/\1/p' "$dir/in.lammps" | head -1)
  awk -v r0="$r0" -v d="$d" '$1 == "neighbor" { gap = sqrt(3) * r0 - d; $2 = (gap > 0) ? 0.75 * gap : 0.3 * r0 } {print}' \
    "$dir/in.lammps" > "$dir/in_tight.lammps"
}
