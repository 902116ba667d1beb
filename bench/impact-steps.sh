#!/usr/bin/env bash
# Fixed against adaptive steps on the disc-impact scene (cases/impact.toml, (3,5)), for docs/stability.md:
# for each impact speed and r_min, the steps taken, wall time, smallest step, energy balance error and the
# closest approach seen in the frames. Prints a Markdown table. About 3 minutes on 2 cores.
#   bench/impact-steps.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
pmfrag=${1:-build}/app/pmfrag
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| speed (cm/s) | step | r_min / r0 | end (s) | steps | wall (s) | smallest step (s) | max abs(balance - balance_0) / KE_0 | closest approach in frames (cm) |"
echo "|---|---|---|---|---|---|---|---|---|"
row() {  # speed step r_min end
  local d="$out/run" speed=$1 step=$2 rmin=$3 end=$4
  local dt_set="time.dt=\"adaptive\""
  [ "$step" = auto ] && dt_set="time.dt=\"auto\""
  "$pmfrag" run cases/impact.toml --out "$d" --force -q --set "$dt_set" --set pair.r_min="$rmin" \
    --set "impactor.0.velocity=[0.0,-$speed.0]" --set time.end="$end" --set output.every=2e-5 > /dev/null
  /usr/bin/python3 - "$d" "$speed" "$step" "$rmin" "$end" <<'PY'
import h5py, json, sys, numpy as np
d, speed, step, rmin, end = sys.argv[1:]
run = json.load(open(d + "/run.json"))
f = h5py.File(d + "/trajectory.h5", "r")
o = f["observables"]
bal, ke = o["energy_balance/value"][:], o["kinetic_energy/value"][:]
x = f["particles/all/position/value"]
close = np.inf
for k in range(x.shape[0]):
    p = x[k]
    r = np.sqrt(((p[:, None, :] - p[None, :, :]) ** 2).sum(-1))
    np.fill_diagonal(r, np.inf)
    close = min(close, r.min())
label = "adaptive" if run["dt_adaptive"] else "fixed %.3g s" % run["dt_s"]
print("| %s | %s | %s | %s | %d | %.2f | %.3g | %.2g | %.4f |" % (speed, label, rmin, end, run["steps"], run["wall_s"],
      run["dt_min_s"], np.abs(bal - bal[0]).max() / ke[0], close))
PY
}
for v in 50 200 1000; do row $v adaptive 0.1 1e-2; done
row 5000 adaptive 0.1 2e-3
row 1000 adaptive 0.5 1e-2
row 1000 auto 0.5 1e-2
row 1000 auto 0.1 1e-3
