#!/usr/bin/env python3
"""The thesis-claim tables of results/README.md, from the stored sweeps and runs.

Reads the sweeps written by `results/regenerate.sh --studies` (their files are made by
scenarios/sweeps/make_thesis_claims.py): results/sweeps/<sweep>/sweep.csv and each
point's epochs.csv and summary.json; and the stored runs results/grid16_monolithic/
(cost after the loads) and results/<run>/trace.csv (body position and velocity errors).
Every comparison is paired: the DSM against a baseline over the windows where both were
measured (summary.json `paired`, written into sweep.csv's paired_* columns;
docs/method.md section 5).

The test (method section 5, chosen before the data): the two-sided exact sign test on
the paired per-window differences, ties left out, with a Holm-Bonferroni correction
over each table's comparisons (the family is the table's cells); a comparison is
**better** or worse when its corrected p is below 0.05. The paired-t 95 % interval of
the mean difference is shown beside it and decides nothing. Every comparison of every
table, with its full numbers, goes to results/claims.csv.

Usage: results/summarize_claims.py [--write README | --check README] [RESULTS_DIR]
Prints the tables as Markdown; with --write, replaces the part of README between the
lines `<!-- claims: begin -->` and `<!-- claims: end -->` with them and writes
RESULTS_DIR/claims.csv; with --check (CI), exits non-zero unless that part and
claims.csv already hold exactly them.
"""
import csv
import io
import json
import math
import os
import re
import statistics
import sys

BEGIN, END = "<!-- claims: begin -->", "<!-- claims: end -->"
# The four settings of every claim: (measure, which D_s).
SETTINGS = [("lookahead", "12"), ("lookahead", "best"), ("online", "12"), ("online", "best")]
STORED = ["grid16_space_cp", "grid16_space_cp_ds2", "grid16_space_cp_online",
          "grid16_space_cp_ds2_online", "grid16_time_cp", "grid16_time_cp_ds2",
          "grid16_space_cp_ramp", "grid16_space_cp_ramp_ds2", "grid16_space_up",
          "grid16_time_up", "tdma4_space_cp", "tdma16_space_cp"]
SIZES = ["0.001", "0.002", "0.003", "0.004", "0.006", "0.008", "0.012"]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class Sweep:
    """One sweep's rows, each with its point's epochs.csv."""

    def __init__(self, root, name):
        self.name = name
        self.dir = os.path.join(root, "sweeps", name)
        self.rows = read_csv(os.path.join(self.dir, "sweep.csv"))

    def row(self, **axes):
        hits = [r for r in self.rows if all(r.get(k) == v for k, v in axes.items())]
        if len(hits) != 1:
            raise SystemExit(f"{self.name}: {len(hits)} points match {axes}")
        return hits[0]

    def epochs(self, row):
        return read_csv(os.path.join(self.dir, "points", row["point"], "epochs.csv"))


def ms(x):
    return f"{float(x) * 1e3:g}"


LEVEL = 0.05  # the sign test's level, after the Holm correction of its table


def sign_p(wins, losses):
    """Two-sided exact sign test of `wins` against `losses` (ties left out)."""
    n = wins + losses
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(min(wins, losses) + 1))
    return min(1.0, 2.0 * tail / 2 ** n)


class Cmp:
    """One paired comparison: the DSM against a baseline over their common windows."""

    def __init__(self, ratio, n, wins, losses, diff, ci):
        self.ratio, self.n, self.wins, self.losses, self.diff = ratio, n, wins, losses, diff
        self.ties = n - wins - losses
        self.ci = ci  # (low, high) of the mean difference, paired t, or None
        self.p = sign_p(wins, losses)

    def t_verdict(self):
        if self.ci is None:
            return "not_significant"
        if self.ci[1] < 0:
            return "better"
        return "worse" if self.ci[0] > 0 else "not_significant"

    def sign_verdict(self, p):
        if p >= LEVEL or self.wins == self.losses:
            return "not_significant"
        return "better" if self.wins > self.losses else "worse"


def paired(row, baseline):
    """The comparison of the DSM with `baseline` in a sweep row (None when it has none)."""
    get = lambda c: row.get(f"paired_{c}_{baseline}", "")
    if row["status"] != "ok" or not get("n"):
        return None
    ci = (float(get("ci_low")), float(get("ci_high"))) if get("ci_low") else None
    return Cmp(float(get("ratio")), int(get("n")), int(get("wins")), int(get("losses")),
               float(get("diff")), ci)


def from_summary(p):
    """The comparison of summary.json's `paired` entry `p`."""
    ci = tuple(p["ci95"]) if p.get("ci95") else None
    return Cmp(p["ratio"], p["n"], p["wins"], p["losses"], p["mean_difference"], ci)


def from_windows(a, b):
    """The comparison of per-window values `a` (the DSM) and `b` (a baseline), windows
    where either is missing left out: the pooled statistic of several runs."""
    pairs = [(x, y) for x, y in zip(a, b) if math.isfinite(x) and math.isfinite(y)]
    n = len(pairs)
    d = [x - y for x, y in pairs]
    mean = sum(d) / n
    sd = statistics.stdev(d)
    half = t975(n - 1) * sd / math.sqrt(n) if n > 1 else None
    ratio = sum(x for x, _ in pairs) / sum(y for _, y in pairs)
    return Cmp(ratio, n, sum(x < y for x, y in pairs), sum(x > y for x, y in pairs), mean,
               (mean - half, mean + half) if half is not None else None)


def t975(df):
    """t(0.975, df): the Student-t quantile, by bisection on its CDF (Simpson's rule on
    the density; standard library only)."""
    c = math.exp(math.lgamma((df + 1) / 2) - math.lgamma(df / 2)) / math.sqrt(df * math.pi)
    pdf = lambda t: c * (1 + t * t / df) ** (-(df + 1) / 2)

    def cdf(x, steps=2000):
        h = x / steps
        s = pdf(0) + pdf(x) + sum((4 if i % 2 else 2) * pdf(i * h) for i in range(1, steps))
        return 0.5 + s * h / 3

    lo, hi = 0.0, 20.0
    for _ in range(50):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cdf(mid) < 0.975 else (lo, mid)
    return (lo + hi) / 2


VERDICT = {"better": "**better**", "worse": "worse", "not_significant": "n.s."}


def fmt_p(p):
    return "<0.001" if p < 0.001 else f"{p:.2g}"


class Family:
    """The comparisons of one table: each cell holds a token until the table is done,
    then the Holm-corrected sign-test p of its comparison fills it."""

    def __init__(self, table):
        self.table, self.items = table, []

    def add(self, cmp, row, column, baseline):
        self.items.append((cmp, row, column, baseline))
        return f"\x00{self.table}:{len(self.items) - 1}\x00"

    def holm(self):
        m = len(self.items)
        order = sorted(range(m), key=lambda i: self.items[i][0].p)
        adj, running = [0.0] * m, 0.0
        for rank, i in enumerate(order):
            running = max(running, min(1.0, (m - rank) * self.items[i][0].p))
            adj[i] = running
        return adj

    def fill(self, text, csv_rows):
        adj = self.holm()
        for i, (c, row, column, baseline) in enumerate(self.items):
            v = c.sign_verdict(adj[i])
            ci = f"[{c.ci[0]:+.3g}, {c.ci[1]:+.3g}]" if c.ci else "[–]"
            cell = (f"{c.ratio:.3f} ({c.n}: {c.wins}/{c.losses}/{c.ties}; {ci}; "
                    f"p {fmt_p(adj[i])} {VERDICT[v]})")
            text = text.replace(f"\x00{self.table}:{i}\x00", cell)
            csv_rows.append([self.table, row, column, baseline, c.n, c.wins, c.losses, c.ties,
                             f"{c.ratio:.6g}", f"{c.diff:.6g}",
                             f"{c.ci[0]:.6g}" if c.ci else "", f"{c.ci[1]:.6g}" if c.ci else "",
                             f"{c.p:.6g}", f"{adj[i]:.6g}", len(self.items), v, c.t_verdict()])
        return text


CSV_HEADER = ["table", "row", "column", "baseline", "n", "wins", "losses", "ties", "ratio",
              "mean_difference", "ci95_low", "ci95_high", "sign_p", "holm_p", "family_size",
              "verdict", "t_verdict"]


def status(row):
    if row["status"] == "ok":
        return "ok"
    return f"diverged at {float(row['diverged_at']):.2f} s ({row['diverged_where']})"


def budget_partner(tau1, budget=400.0, tau_min=0.001):
    return max(1.0 / (budget - 1.0 / tau1), tau_min)


def gap(rows, chan):
    """Mean |live delay − grid optimum| of the controlled channel [ms], and the same for
    no optimization (5 ms)."""
    d = [abs(float(r[f"tau_{chan}_requested"]) - float(r[f"grid_opt_tau_{chan}"])) for r in rows]
    n = [abs(0.005 - float(r[f"grid_opt_tau_{chan}"])) for r in rows]
    return sum(d) / len(d) * 1e3, sum(n) / len(n) * 1e3


def optimum(r, chans, cp):
    """The grid optimum's delays of the two channels `chans` in one epochs.csv row (CP
    stores the controlled one; the other takes the rest of the budget)."""
    first = float(r[f"grid_opt_tau_{chans[0]}"])
    if cp:
        return first, budget_partner(first)
    return first, float(r[f"grid_opt_tau_{chans[1]}"])


def live(r, chans):
    """The delays the live plant ran at in one epochs.csv row."""
    return tuple(float(r[f"tau_{c}_requested"]) for c in chans)


def faster(rows, pair, second_faster=False):
    """Windows where the first of `pair(row)` is the smaller delay (the second, with
    `second_faster`)."""
    count = 0
    for r in rows:
        a, b = pair(r)
        count += (b < a - 1e-12) if second_faster else (a < b - 1e-12)
    return count


def window(rows, lo, hi):
    return [r for r in rows if lo <= float(r["t_start"]) < hi]


def best_size(sweep, sizes=None, **axes):
    """The D_s with the lowest paired DSM/grid ratio among the finished points of
    `sweep` that match `axes` (and have a D_s in `sizes`, if given)."""
    best = None
    for row in sweep.rows:
        if any(row.get(k) != v for k, v in axes.items()):
            continue
        size = row["dsm_size"]
        if sizes is not None and size not in sizes:
            continue
        p = paired(row, "grid")
        if p and (best is None or p.ratio < best[1]):
            best = (size, p.ratio)
    return best[0]


def body_errors(root, run, horizon=3.0, kind="p"):
    """rms error of bodies 1 and 16 against grid16_monolithic over [0, H]: of their
    positions [m] (`kind` "p") or velocities [m/s] ("v")."""
    def load(name):
        return read_csv(os.path.join(root, name, "trace.csv"))

    ref, mine = load("grid16_monolithic"), load(run)
    out = []
    for body in (1, 16):
        sq = [sum((float(a[f"{kind}{ax}_B{body}"]) - float(b[f"{kind}{ax}_B{body}"])) ** 2
                  for ax in "xyz")
              for a, b in zip(ref, mine) if float(a["t"]) <= horizon + 1e-9]
        out.append(math.sqrt(sum(sq) / len(sq)))
    return out


def summary_of(root, run):
    with open(os.path.join(root, run, "summary.json")) as f:
        return json.load(f)


def channels_of(epochs):
    """The channel names of an epochs.csv, in order."""
    return [k[len("tau_"):-len("_requested")] for k in epochs[0]
            if k.startswith("tau_") and k.endswith("_requested")]


def at_optimum(r, chans, cp, tol):
    """Whether the live delays of epochs row `r` are within `tol` [s] of the grid
    optimum on every channel it stores (CP: the controlled one)."""
    ran = live(r, chans)
    if cp:
        return abs(ran[0] - float(r[f"grid_opt_tau_{chans[0]}"])) <= tol + 1e-12
    return all(abs(x - float(r[f"grid_opt_tau_{c}"])) <= tol + 1e-12 for x, c in zip(ran, chans))


def stays(epochs, chans, most=3):
    """Where the live DSM stood: the distinct delay points [ms] with their windows, the
    most visited first."""
    count = {}
    for r in epochs:
        key = tuple(round(x * 1e3, 2) for x in live(r, chans))
        count[key] = count.get(key, 0) + 1
    top = sorted(count.items(), key=lambda kv: (-kv[1], kv[0]))
    shown = ", ".join(f"({', '.join(f'{x:.2f}' for x in k)}) ×{n}" for k, n in top[:most])
    rest = f", {len(top) - most} others" if len(top) > most else ""
    return f"{len(top)} point{'s' if len(top) > 1 else ''}: {shown}{rest}"


def constraint_cost_wins(epochs, summ, minus):
    """Windows where the DSM's constraint cost C alone (the UP objective less the
    penalty b Σ k/τ) is below that of each neighbour in `minus` ({name: channel index}),
    and the windows compared."""
    b = summ["controller"]["problem"]["penalty"]
    ks = [c["k"] for c in summ["channels"]]
    out = []
    for name, i in minus.items():
        wins = n = 0
        for r in epochs:
            taus = [float(r[f"tau_{c['name']}_requested"]) for c in summ["channels"]]
            nb = float(r[f"objective_{name}"])
            if not math.isfinite(nb):
                continue
            own_c = float(r["objective_dsm"]) - b * sum(k / t for k, t in zip(ks, taus))
            taus[i] -= DELTA
            nb_c = nb - b * sum(k / t for k, t in zip(ks, taus))
            n += 1
            wins += own_c < nb_c
        out.append(f"{name.split('_', 1)[1]} {wins}/{n}")
    return "; ".join(out)


DELTA = 0.002  # the DSM's ± δ neighbours [s] (controller.dsm_delta of every sweep)


def tables(root):
    out = []
    csv_rows = []
    say = out.append
    cp = Sweep(root, "dsm_size_cp")
    hold = Sweep(root, "dsm_size_cp_hold")
    up = Sweep(root, "dsm_size_up")
    extra = {n: Sweep(root, f"measure_{n}") for n in ("ramp", "T10", "tdma4", "tdma16", "Ts")}
    TRIO = ("0.001", "0.002", "0.012")  # the sizes the other claims' scenes were tuned over

    best = {(d, m): best_size(cp, distribution=d, measure=m, start="no_opt")
            for d in ("space", "time") for m in ("lookahead", "online")}
    size_of = lambda d, m, which: "0.012" if which == "12" else best[(d, m)]
    heads = [f"{m}, D_s {'12 ms' if w == '12' else 'best'}" for m, w in SETTINGS]

    def done(family, first):
        """Fills the table begun at out[first] with its family's corrected numbers."""
        text = family.fill("\n".join(out[first:]), csv_rows)
        del out[first:]
        out.append(text)

    say("How to read a comparison: `ratio (n: won/lost/tied; [95 % t interval of the mean "
        "paired difference]; p verdict)`. The ratio is DSM/baseline of the means over the "
        "n windows where both were measured; won/lost/tied count those windows; p is the "
        "two-sided exact sign test of won against lost (ties left out), Holm-corrected over "
        "every comparison of its table; **better** and worse mean p < 0.05, n.s. that it is "
        "not. The t interval [m; the UP objective for UP] is shown beside it and decides "
        "nothing (docs/method.md §5). Every comparison with its full numbers, the uncorrected "
        "p and the t interval's own verdict: [claims.csv](claims.csv).")
    say("")

    first = len(out)
    fam = Family("stored_runs")
    say("### The stored controlled runs")
    say("")
    say("Each stored run (`results/<run>/`), the DSM live, against the grid optimum and no "
        "optimization of the same windows. Family: the 24 comparisons of this table.")
    say("")
    say("| run | measure, D_s | DSM vs grid | DSM vs no-opt | status |")
    say("|---|---|---|---|---|")
    for run in STORED:
        summ = summary_of(root, run)
        ctrl, pairs = summ["controller"], summ["paired"]
        state = "ok" if summ["status"] == "ok" else (
            f"diverged at {summ['divergence']['time']:.2f} s")
        say(f"| `{run}` | {ctrl['measure']}, {ctrl['dsm_size'] * 1e3:g} ms | "
            f"{fam.add(from_summary(pairs['grid']), run, 'vs grid', 'grid')} | "
            f"{fam.add(from_summary(pairs['no_opt']), run, 'vs no-opt', 'no_opt')} | {state} |")
    say("")
    done(fam, first)

    first = len(out)
    fam = Family("ds_sweep")
    say("### The D_s sweep (thesis reading, constrained problem)")
    say("")
    say("Every point is the 30-s experiment with the DSM live; the grid optimum, no "
        "optimization and the DSM's ±2 ms neighbours measured every window from the live "
        "state (`results/sweeps/dsm_size_cp/`). Each cell: DSM vs no-opt; DSM vs grid; the "
        "mean gap |τ1 − τ1*| to the grid optimum. Family: every comparison of this table.")
    say("")
    say("| distribution | measure | start | " + " | ".join(f"D_s {ms(s)} ms" for s in SIZES) + " |")
    say("|---|---|---|" + "---|" * len(SIZES))
    for d in ("space", "time"):
        chan = "tau1" if d == "space" else "state"
        for m in ("lookahead", "online"):
            for start in ("no_opt", "9ms"):
                cells = []
                for s in SIZES:
                    r = cp.row(distribution=d, measure=m, start=start, dsm_size=s)
                    if r["status"] != "ok":
                        cells.append(status(r))
                        continue
                    g, _ = gap(cp.epochs(r), chan)
                    where = f"{d} {m} {start} D_s {ms(s)}"
                    mark = " ◀" if start == "no_opt" and s == best[(d, m)] else ""
                    cells.append(f"{fam.add(paired(r, 'no_opt'), where, 'vs no-opt', 'no_opt')}; "
                                 f"{fam.add(paired(r, 'grid'), where, 'vs grid', 'grid')}; "
                                 f"{g:.1f} ms{mark}")
                start_text = "5 ms (no-opt)" if start == "no_opt" else "9 ms"
                say(f"| {d} | {m} | {start_text} | " + " | ".join(cells) + " |")
    say("")
    say("◀ marks the D_s with the lowest DSM/grid from the no-optimization start, the "
        "\"best D_s\" of the claim table: " + "; ".join(
            f"{d} {m} {ms(best[(d, m)])} ms" for d in ("space", "time")
            for m in ("lookahead", "online")) + ". It was chosen on these same runs.")
    say("")
    done(fam, first)

    first = len(out)
    fam = Family("claims")
    say("### The claims, paired, in both measurement modes (thesis reading)")
    say("")
    say("\"Best D_s\" is, per scene and mode, the size with the lowest DSM/grid among those "
        "run: 1–12 ms on CP (marked above; the constrained claims use it), 1, 2, 4, 6, 12 ms "
        "on UP, and 1, 2, 12 ms on the ramp, T = 10 s and TDMA scenes. It is chosen on the "
        "same runs it is reported for. Family: every comparison of this table.")
    say("")
    say("| claim | " + " | ".join(heads) + " |")
    say("|---|" + "---|" * len(SETTINGS))

    def cell_cp(d, m, w, fn):
        r = cp.row(distribution=d, measure=m, start="no_opt", dsm_size=size_of(d, m, w))
        return fn(r, f"{d} CP {m} D_s {ms(r['dsm_size'])}") if r["status"] == "ok" else status(r)

    def vs(r, where, names):
        return "; ".join(f"vs {n.replace('dsm_', '').replace('_', '-')} "
                         f"{fam.add(paired(r, n), where, 'vs ' + n, n)}"
                         if paired(r, n) else f"vs {n}: –" for n in names)

    def follows(r, where, chan="tau1"):
        g, g0 = gap(cp.epochs(r), chan)
        return f"{vs(r, where, ['no_opt', 'grid'])}; gap {g:.1f} ms (no-opt {g0:.1f})"

    say("| space CP: DSM follows the grid optimum, no-opt does not | " + " | ".join(
        f"D_s {ms(size_of('space', m, w))}: " + cell_cp("space", m, w, follows)
        for m, w in SETTINGS) + " |")
    cells = []
    for m, _ in SETTINGS[::2]:
        r = cp.row(distribution="space", measure=m, start="9ms", dsm_size="0.012")
        cells.append(follows(r, f"space CP {m} D_s 12 from 9 ms") if r["status"] == "ok"
                     else status(r))
    say("| the same, D_s 12 ms started at 9 ms (lattice 3, 15, … ms) | "
        f"{cells[0]} | | {cells[1]} | |")

    def extra_cell(name, m, w, fn):
        size = "0.012" if w == "12" else best_size(extra[name], sizes=TRIO, measure=m)
        r = extra[name].row(measure=m, dsm_size=size)
        where = f"{name} {m} D_s {ms(size)}"
        return f"D_s {ms(size)}: " + (fn(r, where) if r["status"] == "ok" else status(r))

    say("| moving optimum (`_ramp`): DSM follows it | " + " | ".join(
        extra_cell("ramp", m, w, lambda r, where: vs(r, where, ["no_opt", "grid"]))
        for m, w in SETTINGS) + " |")

    errors = {("lookahead", "12"): "grid16_space_cp", ("lookahead", "best"): "grid16_space_cp_ds2",
              ("online", "12"): "grid16_space_cp_online",
              ("online", "best"): "grid16_space_cp_ds2_online"}
    ref = body_errors(root, "grid16_space_cp_no_opt")
    cells = []
    for setting in SETTINGS:
        run = errors[setting]
        e = body_errors(root, run)
        cells.append(f"`{run}`: B1 {e[0]:.4f}, B16 {e[1]:.4f} m")
    say("| position errors of bodies 1 and 16 smaller under DSM (rms over [0, 3] s against "
        f"the monolithic run; no-opt: B1 {ref[0]:.4f}, B16 {ref[1]:.4f} m) | "
        + " | ".join(cells) + " |")

    def near(r, where):
        e = cp.epochs(r)
        early, late = window(e, 0, 12), window(e, 12, 24)
        chans = ("tau1", "tau2")
        opt = lambda x: optimum(x, chans, True)
        ran = lambda x: live(x, chans)
        return (f"optimum {faster(early, opt)}/12 and {faster(late, opt, True)}/12; "
                f"DSM {faster(early, ran)}/12 and {faster(late, ran, True)}/12")

    say("| space CP: the borders near the driven body get the smaller delay (windows of "
        "[0, 12) s with τ1 faster and of [12, 24) s with τ2 faster) | " + " | ".join(
            f"D_s {ms(size_of('space', m, w))}: " + cell_cp("space", m, w, near)
            for m, w in SETTINGS) + " |")

    def ten(m, w):
        size = "0.012" if w == "12" else best_size(extra["T10"], measure=m)
        r10 = extra["T10"].row(measure=m, dsm_size=size)
        r1 = cp.row(distribution="space", measure=m, start="no_opt", dsm_size=size)
        p10, p1 = paired(r10, "grid"), paired(r1, "grid")
        t10 = f"{p10.ratio:.3f} ({p10.n} windows)" if p10 else status(r10)
        t1 = f"{p1.ratio:.3f}" if p1 else status(r1)
        return f"D_s {ms(size)}: DSM/grid {t10} at T = 10 s, {t1} at T = 1 s"

    say("| T = 10 s: DSM fails to follow (DSM/grid worse than at T = 1 s; 3 windows a run, "
        "no test) | " + " | ".join(ten(m, w) for m, w in SETTINGS) + " |")

    def up_cell(d, m, w, fn):
        size = "0.012" if w == "12" else best_size(up, distribution=d, measure=m)
        r = up.row(distribution=d, measure=m, dsm_size=size)
        where = f"{d} UP {m} D_s {ms(size)}"
        return f"D_s {ms(size)}: " + (fn(r, where) if r["status"] == "ok" else status(r))

    space_nb = ["dsm_tau1_plus", "dsm_tau1_minus", "dsm_tau2_plus", "dsm_tau2_minus"]
    say("| space UP (b = 5e-4): DSM beats no-opt, {τ1 ± δ, τ2} and {τ1, τ2 ± δ} | " + " | ".join(
        up_cell("space", m, w, lambda r, where: vs(r, where, ["no_opt"] + space_nb))
        for m, w in SETTINGS) + " |")

    def on_c(names):
        def fn(r, where):
            e = up.epochs(r)
            summ = read_json(os.path.join(up.dir, "points", r["point"], "summary.json"))
            return constraint_cost_wins(e, summ, names)
        return fn

    say("| space UP: on the constraint cost C alone (the penalty b Σ k/τ taken out), "
        "windows where the DSM's C is below its −δ neighbours' | " + " | ".join(
            up_cell("space", m, w, on_c({"dsm_tau1_minus": 0, "dsm_tau2_minus": 1}))
            for m, w in SETTINGS) + " |")

    def forces(r, cp_problem, ep):
        e = ep(r)
        chans = ("state", "force")
        opt = lambda x: optimum(x, chans, cp_problem)
        ran = lambda x: live(x, chans)
        return (f"optimum: forces faster {faster(e, opt, True)}/{len(e)}, states "
                f"{faster(e, opt)}; DSM forces faster {faster(e, ran, True)}/{len(e)}")

    say("| time CP: constraint forces get the smaller delay | " + " | ".join(
        f"D_s {ms(size_of('time', m, w))}: " + cell_cp(
            "time", m, w, lambda r, where: forces(r, True, cp.epochs))
        for m, w in SETTINGS) + " |")
    say("| time CP: DSM beats DSM ± δ | " + " | ".join(
        f"D_s {ms(size_of('time', m, w))}: " + cell_cp(
            "time", m, w, lambda r, where: vs(r, where, ["dsm_state_plus", "dsm_state_minus"]))
        for m, w in SETTINGS) + " |")
    time_nb = ["dsm_state_plus", "dsm_state_minus", "dsm_force_plus", "dsm_force_minus"]
    say("| time UP: forces faster than states; DSM beats no-opt and its neighbours | "
        + " | ".join(up_cell("time", m, w, lambda r, where: forces(r, False, up.epochs) + "; "
                             + vs(r, where, ["no_opt"] + time_nb)) for m, w in SETTINGS) + " |")
    say("| time UP: on C alone, windows where the DSM's C is below its −δ neighbours' | "
        + " | ".join(
            up_cell("time", m, w, on_c({"dsm_state_minus": 0, "dsm_force_minus": 1}))
            for m, w in SETTINGS) + " |")
    for name, label in (("tdma4", "4-node"), ("tdma16", "16-node")):
        say(f"| TDMA, {label} scene: DSM beats no-opt through slot lists | " + " | ".join(
            extra_cell(name, m, w, lambda r, where: vs(r, where, ["no_opt", "grid"]))
            for m, w in SETTINGS) + " |")
    say("")
    done(fam, first)

    say("### Where the simplex stood")
    say("")
    say("The delays the live plant ran at, over the 30 windows of each claim-table setting "
        "(ms; the most visited three and how many windows each): the lattice a CP segment "
        "stands on, and the triangles of UP.")
    say("")
    say("| scene | " + " | ".join(heads) + " |")
    say("|---|" + "---|" * len(SETTINGS))
    for d in ("space", "time"):
        chans = ("tau1",) if d == "space" else ("state",)
        say(f"| {d} CP | " + " | ".join(
            f"D_s {ms(size_of(d, m, w))}: " + cell_cp(
                d, m, w, lambda r, where: stays(cp.epochs(r), chans)) for m, w in SETTINGS)
            + " |")
    for d in ("space", "time"):
        chans = ("tau1", "tau2") if d == "space" else ("state", "force")
        say(f"| {d} UP | " + " | ".join(
            up_cell(d, m, w, lambda r, where: stays(up.epochs(r), chans)) for m, w in SETTINGS)
            + " |")
    say("")

    first = len(out)
    fam = Family("hold")
    say("### Sample and hold (`results/sweeps/dsm_size_cp_hold/`)")
    say("")
    say("Family: every comparison of this table.")
    say("")
    say("| distribution | measure | D_s 12 ms: vs no-opt; vs grid | best D_s | at it: vs no-opt; vs grid |")
    say("|---|---|---|---|---|")
    for d in ("space", "time"):
        for m in ("lookahead", "online"):
            b = best_size(hold, distribution=d, measure=m, start="no_opt")
            cells = []
            for s in ("0.012", b):
                r = hold.row(distribution=d, measure=m, start="no_opt", dsm_size=s)
                where = f"hold {d} {m} D_s {ms(s)}"
                cells.append(f"{fam.add(paired(r, 'no_opt'), where, 'vs no-opt', 'no_opt')}; "
                             f"{fam.add(paired(r, 'grid'), where, 'vs grid', 'grid')}"
                             if r["status"] == "ok" else status(r))
            say(f"| {d} | {m} | {cells[0]} | {ms(b)} ms | {cells[1]} |")
    say("")
    done(fam, first)

    seeds_table(root, out, csv_rows, cp)
    figures_table(root, out, csv_rows, cp, hold, up, extra)
    tests_disagree(root, out)

    say("### Cost over time against cost across the delays")
    say("")
    say("Per window of the loaded stretch [1, 24) s of each lookahead run at its best D_s: "
        "how much the best delays gain over equal ones (no-opt/grid, what any optimizer can "
        "win), against how much the cost of the same equal delays changes from one window "
        "to the next (the noise an online measurement compares candidates through).")
    say("")
    say("| run | no-opt/grid per window: mean, max | no-opt cost between consecutive windows: median, max change | no-opt cost over the windows: min–max [m] |")
    say("|---|---|---|---|")
    for d in ("space", "time"):
        r = cp.row(distribution=d, measure="lookahead", start="no_opt", dsm_size=best[(d, "lookahead")])
        e = window(cp.epochs(r), 1, 24)
        no = [float(x["objective_no_opt"]) for x in e]
        gain = [float(x["objective_no_opt"]) / float(x["objective_grid"]) for x in e]
        steps = sorted(max(a, b) / min(a, b) for a, b in zip(no, no[1:]))
        median = statistics.median(steps)  # the mean of the middle two for an even count
        say(f"| {d} CP, D_s {ms(best[(d, 'lookahead')])} ms | {sum(gain) / len(gain):.3f}, "
            f"{max(gain):.3f} | {median:.2f}×, {max(steps):.2f}× | {min(no):.3f}–{max(no):.3f} |")
    say("")

    say("### Landscapes of the 10–11 s window (stored runs)")
    say("")
    say("The window cost over every (τ1, τ2) on the 1 ms grid from the live state at 10 s, "
        "the budget ignored (`landscape.svg`, `summary.json` → `landscape`).")
    say("")
    say("| run | best pair off the line (τ1, τ2) [ms], cost [m] | best on the budget line [ms], cost [m] | diverged forks |")
    say("|---|---|---|---|")
    for run in ("grid16_space_cp", "grid16_space_cp_ds2", "grid16_space_cp_hold",
                "grid16_space_cp_ds2_hold", "grid16_time_cp", "grid16_time_cp_ds2",
                "grid16_time_cp_hold", "grid16_time_cp_ds2_hold"):
        land = summary_of(root, run)["landscape"]
        pair = lambda p: ", ".join(f"{t * 1e3:.3g}" for t in p["taus_s"])
        b, line = land["best"], land["best_on_budget_line"]
        say(f"| `{run}` | ({pair(b)}), {b['cost_m']:.4f} | ({pair(line)}), "
            f"{line['cost_m']:.4f} | {land['diverged_points']} of {land['points']} |")
    say("")

    mono = read_csv(os.path.join(root, "grid16_monolithic", "epochs.csv"))
    late = [float(r["cost"]) for r in window(mono, 24, 30)]
    say("### After the loads (t ≥ 24 s)")
    say("")
    say(f"Monolithic reference (`grid16_monolithic`, no partition, no delay): window cost "
        f"{min(late):.3f}–{max(late):.3f} m over [24, 30) s (mean {sum(late) / len(late):.3f} m).")
    for name in ("grid16_space_cp_no_opt", "grid16_space_cp", "grid16_space_cp_ds2"):
        rows = read_csv(os.path.join(root, name, "epochs.csv"))
        c = [float(r["cost"]) for r in window(rows, 24, 30)]
        say(f"`{name}`: {min(c):.3f}–{max(c):.3f} m (mean {sum(c) / len(c):.3f} m).")
    say("")
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_HEADER)
    w.writerows(csv_rows)
    return "\n".join(out), buf.getvalue()


def read_json(path):
    with open(path) as f:
        return json.load(f)


# The seeded verdicts (scenarios/sweeps/make_thesis_claims.py, SEEDED): sweep, setting,
# the baselines compared, the axis that draws, and the D_s sweep's point of the same
# setting at the stored scene (phase 0 of an ideal scene is that point).
SEEDED = [
    ("seeds_space_cp", "lookahead_1ms", ["no_opt"], "load_phase",
     ("dsm_size_cp", dict(distribution="space", measure="lookahead", start="no_opt", dsm_size="0.001"))),
    ("seeds_space_cp", "lookahead_2ms", ["no_opt"], "load_phase",
     ("dsm_size_cp", dict(distribution="space", measure="lookahead", start="no_opt", dsm_size="0.002"))),
    ("seeds_time_cp", "lookahead_2ms", ["no_opt", "dsm_state_plus", "dsm_state_minus"], "load_phase",
     ("dsm_size_cp", dict(distribution="time", measure="lookahead", start="no_opt", dsm_size="0.002"))),
    ("seeds_time_cp", "online_1ms", ["no_opt"], "load_phase",
     ("dsm_size_cp", dict(distribution="time", measure="online", start="no_opt", dsm_size="0.001"))),
    ("seeds_space_up", "lookahead_12ms",
     ["no_opt", "dsm_tau1_plus", "dsm_tau1_minus", "dsm_tau2_plus", "dsm_tau2_minus"], "load_phase",
     ("dsm_size_up", dict(distribution="space", measure="lookahead", dsm_size="0.012"))),
    ("seeds_tdma4", "lookahead_1ms", ["no_opt"], "rep",
     ("measure_tdma4", dict(measure="lookahead", dsm_size="0.001"))),
    ("seeds_tdma4", "lookahead_2ms", ["no_opt"], "rep",
     ("measure_tdma4", dict(measure="lookahead", dsm_size="0.002"))),
    ("seeds_tdma16", "lookahead_1ms", ["no_opt"], "rep",
     ("measure_tdma16", dict(measure="lookahead", dsm_size="0.001"))),
]


def seeds_table(root, out, csv_rows, cp):
    say = out.append
    first = len(out)
    fam = Family("seeds")
    say("### Verdicts over seeds and load phases")
    say("")
    say("Each verdict measured again over ten draws: on ideal channels the seed draws nothing "
        "(the same scene with seed 7 and 8 gives the same digest), so the draws are ten "
        "phases of the load (both sinusoids shifted by 0°, 36°, …, 324°; 0° is the stored "
        "scene and the D_s sweep's point); on TDMA, ten seeds (clock drift, random walk, sync "
        "error and jitter; `results/sweeps/seeds_*/`). Per draw, the sign test at 5 % on "
        "that draw alone (uncorrected); then all windows of the ten draws pooled into one "
        "paired comparison (Holm over this table's pooled comparisons; windows of one run "
        "are not independent draws, so the pooled p is a reading aid).")
    say("")
    say("| verdict | draws (diverged) | per draw: better / n.s. / worse | DSM/baseline per draw: min–max | the sweep point of the D_s tables | pooled over the draws |")
    say("|---|---|---|---|---|---|")
    for name, setting, baselines, axis, (ref_sweep, ref_axes) in SEEDED:
        sw = Sweep(root, name)
        rows = [r for r in sw.rows if r["setting"] == setting]
        ref_sw = cp if ref_sweep == "dsm_size_cp" else Sweep(root, ref_sweep)
        ref = ref_sw.row(**ref_axes)
        for b in baselines:
            counts = {"better": 0, "not_significant": 0, "worse": 0}
            ratios, a_all, b_all = [], [], []
            diverged = 0
            for r in rows:
                c = paired(r, b)
                if c is None:
                    diverged += 1
                    continue
                counts[c.sign_verdict(c.p)] += 1
                ratios.append(c.ratio)
                e = sw.epochs(r)
                a_all += [float(x["objective_dsm"]) for x in e]
                b_all += [float(x[f"objective_{b}"]) for x in e]
            label = f"`{name}` {setting.replace('_', ' ')}: DSM vs {b.replace('dsm_', '').replace('_', '-')}"
            rc = paired(ref, b)
            ref_text = (f"{rc.ratio:.3f} ({rc.wins}/{rc.losses}/{rc.ties}, "
                        f"{VERDICT[rc.sign_verdict(rc.p)]} alone)") if rc else status(ref)
            if axis == "load_phase":
                zero = [r for r in rows if r["load_phase"] == "0deg"][0]
                same = "; same digest as phase 0" if zero["digest"] == ref["digest"] else \
                    "; differs from phase 0"
                ref_text += same
            pooled = fam.add(from_windows(a_all, b_all), label, "pooled", b) if ratios else "–"
            rng = f"{min(ratios):.3f}–{max(ratios):.3f}" if ratios else "–"
            say(f"| {label} | {len(rows)} ({diverged}) | {counts['better']} / "
                f"{counts['not_significant']} / {counts['worse']} | {rng} | {ref_text} | {pooled} |")
    say("")
    done_text = fam.fill("\n".join(out[first:]), csv_rows)
    del out[first:]
    out.append(done_text)


def figures_table(root, out, csv_rows, cp, hold, up, extra):
    say = out.append
    first = len(out)
    fam = Family("figures")
    say("### The thesis's other figures and rules")
    say("")
    say("Each row from the stored sweeps and runs, per reading and measurement mode where "
        "the data exist (– where none was run). \"At the optimum\": the live delay within "
        "half the grid step of the grid optimum (0.5 ms on CP's 1-ms grid, 1 ms on each "
        "channel of UP's 2-ms grid; a delay midway between two grid points counts when "
        "either is the optimum). Family: the comparisons of this table (the T_s row).")
    say("")
    say("| claim (thesis) | thesis reading, lookahead | thesis reading, online | sample and hold, lookahead | sample and hold, online |")
    say("|---|---|---|---|---|")

    def end_points(sweep, m, cp_problem, tol):
        hits, n, where = 0, 0, []
        for r in sweep.rows:
            if r["measure"] != m:
                continue
            e = [x for x in sweep.epochs(r) if float(x["t_start"]) == 10.0]
            if not e:
                continue
            chans = channels_of(sweep.epochs(r))
            n += 1
            if at_optimum(e[0], chans, cp_problem, tol):
                hits += 1
                start = f" from {r['start'].replace('no_opt', '5ms')}" if "start" in r else ""
                where.append(f"{r['distribution']} D_s {ms(r['dsm_size'])}{start}")
        listed = f" ({', '.join(where)})" if where else ""
        return f"{hits} of {n}{listed}"

    def stored_end_points(hold_reading, m):
        hits, n, names = 0, 0, []
        for d in sorted(os.listdir(root)):
            path = os.path.join(root, d, "summary.json")
            if not d.startswith("grid16_") or not os.path.isfile(path):
                continue
            summ = read_json(path)
            ctrl = summ.get("controller")
            if (not ctrl or ctrl["method"] != "dsm" or ctrl["measure"] != m
                    or d.endswith("_hold") != hold_reading):
                continue
            e = read_csv(os.path.join(root, d, "epochs.csv"))
            e = [x for x in e if float(x["t_start"]) == 10.0 and float(x["t_end"]) == 11.0]
            if not e:
                continue
            n += 1
            cp_problem = ctrl["problem"]["kind"] == "cp"
            if at_optimum(e[0], channels_of(e), cp_problem, 0.0005 if cp_problem else 0.001):
                hits += 1
                names.append(d)
        if n == 0:
            return "none stored"
        return f"{hits} of {n}" + (f" ({', '.join(names)})" if names else "")

    cells = []
    for reading, cps in (("thesis", cp), ("hold", hold)):
        for m in ("lookahead", "online"):
            text = f"CP sweep {end_points(cps, m, True, 0.0005)}"
            if reading == "thesis":
                text += f"; UP sweep {end_points(up, m, False, 0.001)}"
            text += f"; stored runs {stored_end_points(reading == 'hold', m)}"
            cells.append(text)
    say("| the DSM's delays at 10–11 s are the optimum's (Figs 3-13/3-21/3-25/3-29): points "
        "at the optimum | " + " | ".join(cells) + " |")

    def up_bandwidth(m):
        parts, under, n = [], 0, 0
        for d in ("space", "time"):
            for r in up.rows:
                if r["distribution"] != d or r["measure"] != m:
                    continue
                e = up.epochs(r)
                top = max(float(x["bandwidth"]) for x in e)
                n += 1
                under += top <= 400.0
                parts.append(f"{d[0]} {ms(r['dsm_size'])}: {top:.0f}"
                             + ("" if r["status"] == "ok" else " (diverged)"))
        return f"{under} of {n} points ≤ 400 Hz; max per window [Hz]: " + ", ".join(parts)

    def stored_up_bandwidth():
        parts = []
        for d in ("grid16_space_up_hold", "grid16_time_up_hold"):
            e = read_csv(os.path.join(root, d, "epochs.csv"))
            parts.append(f"`{d}` (12 ms) max {max(float(x['bandwidth']) for x in e):.0f} Hz")
        return "; ".join(parts)

    say("| UP: the bandwidth stays under B = 400 Hz (Figs 3-18/3-26; s = space, t = time, "
        "then D_s [ms]) | " + f"{up_bandwidth('lookahead')} | {up_bandwidth('online')} | "
        f"{stored_up_bandwidth()} | – |")

    def up_tracks(m):
        parts = []
        for d in ("space", "time"):
            for r in up.rows:
                if r["distribution"] != d or r["measure"] != m:
                    continue
                e = up.epochs(r)
                chans = channels_of(e)
                at = sum(at_optimum(x, chans, False, 0.001) for x in e)
                dist = sum(math.dist(live(x, chans), [float(x[f"grid_opt_tau_{c}"]) for c in chans])
                           for x in e) / len(e) * 1e3
                parts.append(f"{d[0]} {ms(r['dsm_size'])}: {at}/{len(e)}, {dist:.1f} ms")
        return "; ".join(parts)

    def stored_up_tracks():
        parts = []
        for d in ("grid16_space_up_hold", "grid16_time_up_hold"):
            e = read_csv(os.path.join(root, d, "epochs.csv"))
            chans = channels_of(e)
            at = sum(at_optimum(x, chans, False, 0.001) for x in e)
            parts.append(f"`{d}` (12 ms) {at}/{len(e)}")
        return "; ".join(parts)

    say("| UP: the DSM's point is the optimum it tracks (Figs 3-20/3-28): windows at the "
        "optimum, mean distance to it | " + f"{up_tracks('lookahead')} | {up_tracks('online')} | "
        f"{stored_up_tracks()} | – |")

    hold_errors = {"lookahead": ["grid16_space_cp_hold", "grid16_space_cp_ds2_hold"]}
    thesis_errors = {"lookahead": ["grid16_space_cp", "grid16_space_cp_ds2"],
                     "online": ["grid16_space_cp_online", "grid16_space_cp_ds2_online"]}

    def velocity(runs, ref):
        r = body_errors(root, ref, kind="v")
        text = [f"no-opt B1 {r[0]:.4f}, B16 {r[1]:.4f}"]
        for run in runs:
            e = body_errors(root, run, kind="v")
            size = summary_of(root, run)["controller"]["dsm_size"] * 1e3
            text.append(f"D_s {size:g}: B1 {e[0]:.4f}, B16 {e[1]:.4f}")
        return "; ".join(text) + " m/s"

    say("| velocity errors of bodies 1 and 16 smaller under DSM (Figs 3-14/3-15; rms over "
        "[0, 3] s against the monolithic run) | "
        f"{velocity(thesis_errors['lookahead'], 'grid16_space_cp_no_opt')} | "
        f"{velocity(thesis_errors['online'], 'grid16_space_cp_no_opt')} | "
        f"{velocity(hold_errors['lookahead'], 'grid16_space_cp_no_opt_hold')} | – |")

    ramp = extra["ramp"]

    def d_smin(m):
        rows = [r for r in ramp.rows if r["measure"] == m]
        slopes = []
        for r in rows:
            e = ramp.epochs(r)
            t = [float(x["t_start"]) for x in e]
            y = [float(x["grid_opt_tau_tau1"]) for x in e]
            tm, ym = sum(t) / len(t), sum(y) / len(y)
            slopes.append(sum((a - tm) * (b - ym) for a, b in zip(t, y))
                          / sum((a - tm) ** 2 for a in t))
        v = sum(abs(x) for x in slopes) / len(slopes)
        mr, period = 5, 1.0
        dmin = (mr + 1) * v * period
        parts = []
        for r in sorted(rows, key=lambda r: float(r["dsm_size"])):
            if r["status"] != "ok":
                parts.append(f"{ms(r['dsm_size'])}: {status(r)}")
                continue
            g, _ = gap(ramp.epochs(r), "tau1")
            below = "<" if float(r["dsm_size"]) < dmin else "≥"
            parts.append(f"{ms(r['dsm_size'])} ({below}): DSM/grid {paired(r, 'grid').ratio:.3f}, "
                         f"gap {g:.1f} ms")
        return (f"optimum drifts v = {v * 1e3:.3f} ms/s (least-squares slope of τ1*, mean over "
                f"the {len(rows)} points), D_smin = 6 v T = {dmin * 1e3:.2f} ms; per D_s [ms]: "
                + "; ".join(parts))

    say("| §3.3.3: a moving optimum needs D_s ≥ D_smin = (m_r + 1) v T (ramp scene, m_r = 5, "
        f"T = 1 s) | {d_smin('lookahead')} | {d_smin('online')} | – | – |")

    ts = extra["Ts"]

    def server(m):
        parts = []
        for r in ts.rows:
            if r["measure"] != m:
                continue
            where = f"tdma4 {m} D_s 2 T_s {r['T_s']}"
            c = paired(r, "no_opt")
            parts.append(f"T_s {r['T_s']}: " + (fam.add(c, where, "vs no-opt", "no_opt")
                                                 if c else status(r)))
        return "; ".join(parts)

    say("| §4.2: the server's period T_s (decision lag T_s m_r, 4-node TDMA, D_s 2 ms): DSM vs "
        f"no-opt | {server('lookahead')} | {server('online')} | – | – |")
    say("")
    text = fam.fill("\n".join(out[first:]), csv_rows)
    del out[first:]
    out.append(text)


def tests_disagree(root, out):
    """How often the t interval's verdict and the sign test's (both uncorrected, at 5 %)
    differ over every comparison against no-opt or a ± δ neighbour in the stored sweeps
    with 30 windows a point (all but measure_T10)."""
    total = differ = t_only = sign_only = opposite = 0
    names = sorted(d for d in os.listdir(os.path.join(root, "sweeps"))
                   if d.startswith(("dsm_size_", "measure_", "seeds_")) and d != "measure_T10")
    for name in names:
        sw = Sweep(root, name)
        bases = sorted({k[len("paired_n_"):] for k in sw.rows[0] if k.startswith("paired_n_")})
        for r in sw.rows:
            for b in bases:
                c = paired(r, b)
                if b == "grid" or c is None:
                    continue
                total += 1
                tv, sv = c.t_verdict(), c.sign_verdict(c.p)
                if tv != sv:
                    differ += 1
                    if sv == "not_significant":
                        t_only += 1
                    elif tv == "not_significant":
                        sign_only += 1
                    else:
                        opposite += 1
    out.append("### The two tests, uncorrected, on every stored comparison")
    out.append("")
    out.append(f"Over the finished points of the stored sweeps with 30 windows a point "
               f"({', '.join(names)}), {total} comparisons of the DSM against no-opt or a "
               f"± δ neighbour: the t interval's verdict and the sign test's, each at 5 % "
               f"uncorrected, differ in {differ} ({t_only} significant by t only, "
               f"{sign_only} by the sign test only, {opposite} significant both ways in "
               f"opposite directions).")
    out.append("")


def main(argv):
    mode, readme = None, None
    if len(argv) >= 2 and argv[0] in ("--write", "--check"):
        mode, readme, argv = argv[0], argv[1], argv[2:]
    root = argv[0] if argv else os.path.dirname(os.path.abspath(__file__))
    text, table = tables(root)
    claims = os.path.join(root, "claims.csv")
    if mode is None:
        print(text)
        return
    with open(readme) as f:
        doc = f.read()
    if BEGIN not in doc or END not in doc:
        raise SystemExit(f"{readme}: no `{BEGIN}` … `{END}` section")
    head, rest = doc.split(BEGIN, 1)
    old, tail = rest.split(END, 1)
    if mode == "--check":
        if old != "\n" + text + "\n":
            raise SystemExit(f"{readme}: the claim tables differ from the stored sweeps and runs; "
                             f"rewrite them with `results/summarize_claims.py --write {readme}`")
        stored = open(claims, newline="").read() if os.path.isfile(claims) else None
        if stored != table:
            raise SystemExit(f"{claims}: differs from the stored sweeps and runs; rewrite it "
                             f"with `results/summarize_claims.py --write {readme}`")
        print(f"{readme} and {claims}: the claim tables match the stored sweeps and runs")
        return
    for path, body in ((readme, head + BEGIN + "\n" + text + "\n" + END + tail), (claims, table)):
        tmp = path + ".tmp.claims"
        with open(tmp, "w", newline="") as f:
            f.write(body)
        os.replace(tmp, path)


if __name__ == "__main__":
    main(sys.argv[1:])
