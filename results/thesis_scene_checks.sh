#!/usr/bin/env bash
# Reproduces the figures quoted in docs/guide.md "What the thesis scene does in this model" and
# "Partitioned co-simulation": variants of the shipped thesis scenarios (integrator, K,
# delays, ghost mode) run at full trace resolution in a scratch directory.
# Usage: results/thesis_scene_checks.sh [SCRATCH_DIR]
set -uo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet || exit 1
bin=$PWD/target/release/dsmcosim
tmp=${1:-$(mktemp -d)}
python3 - "$tmp" <<'PY'
import json, sys
tmp = sys.argv[1]
mono = json.load(open("scenarios/grid16_monolithic.json"))
space = json.load(open("scenarios/grid16_space_fixed.json"))
def variant(name, base, **changes):
    s = json.loads(json.dumps(base))
    s["output"]["decimation"] = 1
    for key, value in changes.items():
        if key == "tau":
            for c in s["channels"]:
                c["tau"] = value
        elif key == "k":
            s["stabilizer"]["k"] = value
        elif key == "ghosts":
            s["partition"]["ghosts"] = value
        elif key == "bound":
            s["divergence"] = {"max_violation": value}
        else:
            s[key] = value
    json.dump(s, open(f"{tmp}/{name}.json", "w"), indent=1)
variant("mono_euler", mono)
variant("mono_rk4", mono, integrator="rk4")
variant("mono_rk4_k100", mono, integrator="rk4", k=100.0)
variant("mono_euler_k100", mono, k=100.0)
variant("nodes4_1ms_euler", space, tau=0.001, bound=100.0)
variant("nodes4_5ms_euler", space, bound=100.0)
variant("nodes4_5ms_rk4", space, integrator="rk4", bound=100.0)
variant("nodes4_1ms_hold", space, tau=0.001, ghosts="hold")
PY
for n in mono_euler mono_rk4 mono_rk4_k100 mono_euler_k100 nodes4_1ms_euler nodes4_5ms_euler nodes4_5ms_rk4 nodes4_1ms_hold; do
  echo "== $n: $("$bin" run "$tmp/$n.json" --out "$tmp/$n" 2>&1 | head -1 | cut -c1-140)"
  python3 - "$tmp/$n/trace.csv" <<'PY'
import csv, sys
r = csv.reader(open(sys.argv[1])); h = next(r)
wi = [i for i, c in enumerate(h) if c.startswith("w_")]
vi = [i for i, c in enumerate(h) if c[:2] in ("vx", "vy", "vz")]
m12 = mall = vmax = 0.0
for row in r:
    t = float(row[0]); m = max(abs(float(row[i])) for i in wi)
    if t < 12: m12 = max(m12, m)
    mall = max(mall, m); vmax = max(vmax, max(abs(float(row[i])) for i in vi))
print(f"   max|w| over [0,12) s: {m12:.4f} m; over the run: {mall:.4f} m; max |velocity component|: {vmax:.1f} m/s")
PY
  echo "   internal kinetic energy [J] by time [s]: $(python3 results/kinetic_energy.py "$tmp/$n/trace.csv" 2)"
done
echo "(runs in $tmp)"
