#!/usr/bin/env python3
"""A delay controller written in Python against the DSM on the thesis's space CP,
paired window against window from the same states (docs/python.md, "Your own
controller against the DSM").

The scene is scenarios/grid16_space_cp_ds2.json: the thesis's 4x4 net on 4 nodes, body
1 driven over [0, 12) s and body 16 over [12, 24) s, 30 s in windows of 1 s, the
constrained problem (the controller moves tau1, and tau2 = 1 / (400 Hz - 1/tau1) takes
the rest of the budget, so tau1 lies in [2.63, 50] ms), and the DSM with a 2-ms simplex.

1. The DSM runs through the package exactly as `dsmcosim run` runs it (lookahead: each
   candidate measured on a fork; the grid, no-optimization and other baselines measured
   beside it). Its epochs.csv holds every window's decision and cost.
2. The same scene without its controller is then steered from Python along the DSM's
   decisions (`CoSim.set_periods` at each window boundary), so the live state at every
   window start is the DSM's own: the script checks that each replayed window costs what
   the DSM's run measured, to the bit, and that no optimization measured here on a fork
   costs what the run's own baseline measured, to the bit.
3. In every window, from that state, scipy's bounded scalar minimizer (Brent's method,
   `minimize_scalar`, at most 12 evaluations, tolerance 0.25 ms) chooses tau1, each
   evaluation the window's cost on a fork of the whole co-simulation (as the DSM's
   candidates are measured); a candidate that diverges within the window scores 10 m,
   and if every try diverged scipy's choice is equal delays.

So scipy and the DSM are compared window against window, from the same states over the
same windows, exactly as `dsmcosim run` compares the DSM with its baselines; each is also
compared with no optimization and with the grid optimum (the run's 1-ms grid) of the same
windows. At the end the replay's decisions, `CoSim.schedule()`, are run through the
command line's path as a scenario `schedule`: its dynamics digest is the DSM run's.

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


def main():
    scene = REPO / "scenarios" / "grid16_space_cp_ds2.json"
    dsm = dsmcosim.run(scene)
    epochs = dsm.epochs
    doc = json.loads(scene.read_text())
    del doc["controller"]
    doc["name"] = "grid16_space_cp_python"
    sim = dsmcosim.CoSim(doc, base_dir=REPO / "scenarios")
    rows, evaluations = [], []
    print("window [s] | DSM tau1 [ms], cost [m] | scipy tau1 [ms] (evaluations), cost [m] | "
          "no-opt [m] | grid optimum tau1 [ms], cost [m]")
    for w in epochs.itertuples():
        start, t_end = float(w.t_start), float(w.t_end)
        assert sim.now == start, (sim.now, start)
        found = minimize_scalar(lambda x: measure(sim, t_end, x), bounds=(LOW, TAU_MAX),
                                method="bounded", options={"xatol": 2.5e-4, "maxiter": 12})
        tau1, scipy_cost = float(found.x), float(found.fun)
        if scipy_cost >= PENALTY:
            tau1 = 0.005                     # every try diverged: fall back to equal delays
            scipy_cost = measure(sim, t_end, tau1)
        no_opt = measure(sim, t_end, 0.005)
        if no_opt != w.objective_no_opt:
            raise SystemExit(f"window {start:g}: no optimization measured here, {no_opt!r}, "
                             f"is not the run's baseline, {w.objective_no_opt!r}")
        sim.set_periods([w.tau_tau1_requested, w.tau_tau2_requested])
        sim.advance(t_end)
        live = sim.window_cost()[1]
        if live != w.cost:
            raise SystemExit(f"window {start:g}: the replay costs {live!r}, the DSM's run "
                             f"measured {w.cost!r}")
        rows.append((live, scipy_cost, no_opt, w.objective_grid))
        evaluations.append(found.nfev)
        print(f"{start:g}–{t_end:g} | {w.tau_tau1_requested * 1e3:.2f}, {live:.4f} | "
              f"{tau1 * 1e3:.2f} ({found.nfev}), {scipy_cost:.4f} | {no_opt:.4f} | "
              f"{w.grid_opt_tau_tau1 * 1e3:g}, {w.objective_grid:.4f}")
    if not sim.finished:
        sim.advance(sim.duration)
    dsm_cost, scipy_cost, no_opt, grid_best = zip(*rows)
    print()
    print("Every replayed window cost what the DSM's run measured, and no optimization "
          "what its baseline measured, to the bit.")
    print("scipy vs the DSM, window against window:", paired(scipy_cost, dsm_cost))
    print("scipy vs no optimization:", paired(scipy_cost, no_opt))
    print("the DSM vs no optimization:", paired(dsm_cost, no_opt))
    print("scipy vs the grid optimum:", paired(scipy_cost, grid_best))
    print("the DSM vs the grid optimum:", paired(dsm_cost, grid_best))
    print(f"measurements a window: scipy {sum(evaluations) / len(evaluations):.1f} on "
          f"average ({min(evaluations)}–{max(evaluations)}), the DSM "
          f"{epochs['measurements'].mean():.1f} on average")
    doc["schedule"] = sim.schedule()
    replayed = dsmcosim.run(doc, base_dir=REPO / "scenarios")
    same = replayed.summary["dynamics_digest"] == dsm.summary["dynamics_digest"]
    print(f"the DSM's decisions as a scenario schedule: dynamics digest "
          f"{replayed.summary['dynamics_digest'][:16]}…, the DSM run's "
          f"{dsm.summary['dynamics_digest'][:16]}…: {'the same' if same else 'DIFFERENT'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
