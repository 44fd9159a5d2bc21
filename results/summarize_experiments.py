#!/usr/bin/env python3
"""Prints the figures results/README.md quotes for the thesis experiments, from the
stored runs in results/<scenario>/ (summary.json and epochs.csv), in both readings of
delay: the thesis reading (<scenario>, latency = tau) and sample-and-hold (<scenario>_hold).
Usage: results/summarize_experiments.py [RESULTS_DIR]"""
import csv, glob, json, os, sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
names = ["grid16_space_cp", "grid16_space_cp_ds2", "grid16_space_cp_T10", "grid16_space_cp_ramp",
         "grid16_space_cp_ramp_ds2", "grid16_space_up", "grid16_time_cp", "grid16_time_cp_ds2",
         "grid16_time_up", "tdma4_space_cp", "tdma16_space_cp"]
names = [v for n in names for v in (n, n + "_hold")]

def mean(xs):
    xs = [x for x in xs if x == x]
    return sum(xs) / len(xs) if xs else float("nan")

for n in names:
    d = os.path.join(root, n)
    if not os.path.isfile(os.path.join(d, "summary.json")):
        print(f"{n}: not found"); continue
    s = json.load(open(os.path.join(d, "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(d, "epochs.csv"))))
    costs = {k[len("unpaired_mean_cost_"):]: v for k, v in s.items() if k.startswith("unpaired_mean_cost_")}
    order = sorted(costs, key=costs.get)
    print(f"== {n} ({s['status']}, {s['controller']['problem']['kind']}, D_s = {s['controller']['dsm_size']}, "
          f"T = {float(rows[0]['t_end']) - float(rows[0]['t_start']):g} s)")
    print("   mean cost by method over its own windows (best first; not a comparison): "
          + ", ".join(f"{m} {costs[m]:.4f}" for m in order))
    # Comparisons: the live method against each baseline over the windows where both
    # were measured (summary.json's `paired`, method §5).
    for other, p in s.get("paired", {}).items():
        ci = p["ci95"]
        ci_text = f"[{ci[0]:+.2e}, {ci[1]:+.2e}]" if ci else "–"
        ratio = p["ratio"] if p["ratio"] is not None else float("nan")
        print(f"   {s['controller']['method']} vs {other}: n {p['n']} (excluded {p['excluded']}), "
              f"ratio {ratio:.3f}, won {p['wins']} lost {p['losses']}, "
              f"mean difference 95 % CI {ci_text}, sign test p {p['sign_test_p']:.3f}: {p['verdict']}")
    chans = [c["name"] for c in s["channels"]]
    opt_cols = [c for c in rows[0] if c.startswith("grid_opt_tau_")]
    for r in rows:
        if float(r["t_start"]) == 10.0 or (len(rows) < 10 and float(r["t_start"]) <= 10.0 < float(r["t_end"])):
            live = ", ".join(f"{c} {float(r[f'tau_{c}_requested']) * 1e3:.2f} ms" for c in chans)
            opt = ", ".join(f"{c[len('grid_opt_tau_'):]} {float(r[c]) * 1e3:.0f} ms" for c in opt_cols)
            print(f"   window starting 10 s: grid optimum {opt}; DSM ran at {live}")
    # Which channel is faster under the grid optimum, over the windows while body 1 is driven.
    if s["controller"]["problem"]["kind"] == "cp" and opt_cols:
        budget = s["controller"]["problem"]["budget"]
        early = [r for r in rows if float(r["t_end"]) <= 12.0]
        faster_first = equal = 0
        for r in early:
            t1 = float(r[opt_cols[0]]); t2 = 1.0 / (budget - 1.0 / t1)
            faster_first += t1 < t2 - 1e-12
            equal += abs(t1 - t2) <= 1e-12
        print(f"   windows in [0, 12) s where the grid optimum gives {chans[0]} the smaller delay: "
              f"{faster_first} of {len(early)}; equal delays: {equal}; {chans[1]} smaller: "
              f"{len(early) - faster_first - equal}")
        gap = mean([abs(float(r[f'tau_{chans[0]}_requested']) - float(r[opt_cols[0]])) for r in rows])
        print(f"   mean |DSM {chans[0]} − grid optimum| = {gap * 1e3:.2f} ms")
        opt_ms = [round(float(r[opt_cols[0]]) * 1e3) for r in rows]
        hist = {v: opt_ms.count(v) for v in sorted(set(opt_ms))}
        print(f"   grid optimum {chans[0]} [ms]: windows per value " +
              ", ".join(f"{v}: {k}" for v, k in hist.items()))
        live_ms = [round(float(r[f'tau_{chans[0]}_requested']) * 1e3, 1) for r in rows]
        common = max(sorted(set(live_ms)), key=live_ms.count)
        print(f"   DSM {chans[0]} at its most common value {common} ms in {live_ms.count(common)} of {len(rows)} windows")
    elif opt_cols:
        faster = sum(float(r[opt_cols[1]]) < float(r[opt_cols[0]]) for r in rows)
        print(f"   windows where the grid optimum gives {opt_cols[1][len('grid_opt_tau_'):]} the smaller delay: "
              f"{faster} of {len(rows)}; DSM: "
              f"{sum(float(r[f'tau_{chans[1]}_requested']) < float(r[f'tau_{chans[0]}_requested']) for r in rows)} of {len(rows)}")

# Wall time of every stored run (results/README.md's "Runs and time to regenerate" table).
print()
print("| stored run | status | wall time [s] |")
print("|---|---|---|")
total = 0.0
for summary in sorted(glob.glob(os.path.join(root, "*", "summary.json"))):
    d = os.path.dirname(summary)
    if d.endswith(".new"):
        continue
    s = json.load(open(summary))
    total += s["wall_seconds"]
    print(f"| {os.path.basename(d)} | {s['status']} | {s['wall_seconds']:.1f} |")
print(f"| **sum** | | **{total:.1f}** |")
