#!/usr/bin/env python3
"""Internal kinetic energy (centre-of-mass motion removed) of a run, from its trace.csv,
one value per whole second. Assumes unit masses (the thesis grid).
Usage: results/kinetic_energy.py DIR/trace.csv [every_s]"""
import csv, re, sys

path = sys.argv[1]
every = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
rows = csv.DictReader(open(path))
bodies = sorted({int(m.group(1)) for c in rows.fieldnames for m in [re.fullmatch(r"vx_B(\d+)", c)] if m})
out = []
for row in rows:
    t = float(row["t"])
    if abs(t / every - round(t / every)) > 1e-9:
        continue
    v = [[float(row[f"v{a}_B{i}"]) for a in "xyz"] for i in bodies]
    vc = [sum(x[k] for x in v) / len(v) for k in range(3)]
    ke = sum((x[k] - vc[k]) ** 2 for x in v for k in range(3)) / 2
    out.append(f"{t:g}:{ke:.0f}")
print(" ".join(out))
