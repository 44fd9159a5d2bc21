#!/usr/bin/env python3
"""A delay controller written in Python against the thesis's space CP, compared with the
DSM and with equal delays, paired over windows (docs/python.md, "Your own controller
against the DSM").

The scene is scenarios/grid16_space_cp.json (the thesis's 4x4 net on 4 nodes, body 1
driven over [0, 12) s and body 16 over [12, 24) s, 30 s, windows of 1 s) without its
controller: Python is the controller. The constrained problem is the thesis's: the
controller moves tau1, and tau2 = 1 / (400 Hz - 1/tau1) takes the rest of the budget, so
tau1 lies in [2.63, 50] ms. Every window, from the live state:

- scipy's bounded scalar minimizer (Brent's method, `minimize_scalar`, at most 12
  evaluations, tolerance 0.25 ms) chooses tau1, each evaluation the window's cost on a
  fork of the whole co-simulation (lookahead, as the DSM's candidates are measured); a
  candidate that diverges within the window scores 10 m, and if every try diverged the
  live run takes equal delays;
- no optimization (5, 5 ms) and the grid optimum (tau1 on the 1 ms grid) are measured on
  forks of the same state, over the same window;
- the live run then goes on at scipy's choice.

So scipy is compared with no optimization and with the grid on the same windows, from
the same states, exactly as `dsmcosim run` compares the DSM with its baselines; the DSM's
own comparisons are read from the stored run results/grid16_space_cp_ds2 (D_s 2 ms) and
results/grid16_space_cp (the thesis's D_s 12 ms). The DSM and scipy each drive their own
live run, so they are compared through the same baselines, not window against window.

Needs the package (`pip install .`) and scipy. Run from the checkout:

    python docs/python_dsm_vs_scipy.py > docs/python_dsm_vs_scipy.txt
"""

import json
import math
import sys
from pathlib import Path

from scipy.optimize import minimize_scalar
from scipy.stats import binomtest, t as student_t

import dsmcosim

REPO = Path(__file__).resolve().parents[1]
BUDGET, TAU_MIN, TAU_MAX = 400.0, 0.001, 0.05
LOW = 1.0 / (BUDGET - 1.0 / TAU_MAX)          # the smallest tau1 the budget allows
PENALTY = 10.0                                # [m], the score of a diverging candidate


def partner(tau1):
    """tau2 when tau1 takes its share of the budget (at least tau_min)."""
    return max(1.0 / (BUDGET - 1.0 / tau1), TAU_MIN)


def measure(sim, t_end, tau1):
    """The cost of the window [now, t_end) at (tau1, its partner), on a fork."""
    trial = sim.fork()
    trial.set_periods([tau1, partner(tau1)])
    try:
        trial.advance(t_end)
    except dsmcosim.DsmcosimError:
        # A candidate that diverges within the window. The DSM scores it +inf; Brent's
        # parabolic steps need numbers, so here it scores PENALTY, more than any window
        # of this scene costs.
        return PENALTY
    return trial.window_cost()[1]


def paired(a, b):
    """The paired comparison the tool prints (docs/method.md section 5): windows, wins,
    ratio of the means, mean difference with its 95 % t interval, sign test, verdict."""
    pairs = [(x, y) for x, y in zip(a, b) if math.isfinite(x) and math.isfinite(y)]
    n = len(pairs)
    d = [x - y for x, y in pairs]
    wins, losses = sum(x < y for x, y in pairs), sum(x > y for x, y in pairs)
    mean = sum(d) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in d) / (n - 1))
    half = student_t.ppf(0.975, n - 1) * sd / math.sqrt(n)
    p = binomtest(wins, wins + losses).pvalue if wins + losses else 1.0
    verdict = "better" if mean + half < 0 else "worse" if mean - half > 0 else "not significant"
    ratio = sum(x for x, _ in pairs) / sum(y for _, y in pairs)
    return (f"ratio {ratio:.3f} ({wins}/{n} windows won, {losses} lost), mean difference "
            f"95 % CI [{mean - half:+.4f}, {mean + half:+.4f}] m, sign test p {p:.3g}: {verdict}")


def stored(run, baseline):
    """The DSM's paired comparison from a stored run's summary.json, in the same words."""
    p = json.loads((REPO / "results" / run / "summary.json").read_text())["paired"][baseline]
    lo, hi = p["ci95"]
    return (f"ratio {p['ratio']:.3f} ({p['wins']}/{p['n']} windows won, {p['losses']} lost), "
            f"mean difference 95 % CI [{lo:+.4f}, {hi:+.4f}] m, sign test p "
            f"{p['sign_test_p']:.3g}: {p['verdict'].replace('_', ' ')}")


def main():
    doc = json.loads((REPO / "scenarios" / "grid16_space_cp.json").read_text())
    del doc["controller"]
    doc["name"] = "grid16_space_cp_python"
    sim = dsmcosim.CoSim(doc, base_dir=REPO / "scenarios")
    grid = [round(LOW + 0.0005, 4)] + [k / 1000 for k in range(3, 51)]
    rows = []
    print("window [s] | scipy tau1 [ms] (evaluations) | scipy cost [m] | no-opt [m] | "
          "grid optimum tau1 [ms], cost [m]")
    while not sim.finished:
        t_end = sim.now + 1.0
        found = minimize_scalar(lambda x: measure(sim, t_end, x), bounds=(LOW, TAU_MAX),
                                method="bounded", options={"xatol": 2.5e-4, "maxiter": 12})
        tau1 = float(found.x)
        if found.fun >= PENALTY:
            tau1 = 0.005                     # every try diverged: fall back to equal delays
        costs = {g: measure(sim, t_end, g) for g in grid}
        best = min(costs, key=costs.get)
        no_opt = measure(sim, t_end, 0.005)
        start = sim.now
        sim.set_periods([tau1, partner(tau1)])
        try:
            sim.advance(t_end)
        except dsmcosim.DsmcosimError as e:
            print(f"{start:g}–{t_end:g} | {tau1 * 1e3:.2f} ({found.nfev}) | the live run "
                  f"diverged: {e} | {no_opt:.4f} | {best * 1e3:g}, {costs[best]:.4f}")
            break
        live = sim.window_cost()[1]
        rows.append((live, no_opt, costs[best]))
        print(f"{start:g}–{t_end:g} | {tau1 * 1e3:.2f} ({found.nfev}) | {live:.4f} | "
              f"{no_opt:.4f} | {best * 1e3:g}, {costs[best]:.4f}")
    live, no_opt, grid_best = zip(*rows)
    print()
    print(f"digest of the scipy-driven run: {sim.digest}")
    print("scipy vs no optimization:", paired(live, no_opt))
    print("scipy vs the grid optimum:", paired(live, grid_best))
    for run, label in (("grid16_space_cp_ds2", "DSM, D_s 2 ms"),
                       ("grid16_space_cp", "DSM, D_s 12 ms (the thesis's)")):
        print(f"{label} vs no optimization (stored run {run}):", stored(run, "no_opt"))
        print(f"{label} vs the grid optimum (stored run {run}):", stored(run, "grid"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
