#!/usr/bin/env python3
"""Load dsmcosim outputs with pandas and redraw two figures with matplotlib.

Usage:
    python3 docs/pandas_example.py RUN_DIR SWEEP_DIR OUT_DIR

RUN_DIR is a directory written by `dsmcosim run SCENARIO --out RUN_DIR` (trace.csv,
epochs.csv, summary.json); SWEEP_DIR one written by `dsmcosim sweep SWEEP.json --out
SWEEP_DIR` (sweep.csv). OUT_DIR (created if missing) receives

    constraints.png  the constraint violation w [m] of links L1 and L2 against time,
                     from trace.csv (the run's own constraints.svg draws the same);
    mean_cost.png    the mean cost [m] against the sweep's first axis (one line per value
                     of the second, averaged over any others), from sweep.csv.

Every CSV dsmcosim writes loads with a plain `pandas.read_csv`: one header line, numbers
in Rust's shortest round-trip form (read back bit for bit), an empty field where a run
produced no value (NaN), text fields quoted only where they hold a comma, and no cell
holding JSON. The checks below fail (exit 1) if a column that should be numeric is not.

Needs pandas and matplotlib (`pip install pandas matplotlib`). CI runs this script on a
fresh run and a tiny sweep (.ci/run).
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
from pandas.api.types import is_numeric_dtype  # noqa: E402


def require_numeric(df, columns, name):
    """Fail unless every column in `columns` was read as a number type."""
    bad = [c for c in columns if not is_numeric_dtype(df[c])]
    if bad:
        sys.exit(f"{name}: columns not numeric: {', '.join(f'{c} ({df[c].dtype})' for c in bad)}")


def require_no_json(df, name):
    """Fail if a text column holds a JSON object or array."""
    for c in df.columns:
        if is_numeric_dtype(df[c]):
            continue
        cells = df[c].dropna().astype(str).str.strip()
        if cells.str.match(r"^[\[{]").any():
            sys.exit(f"{name}: column {c} holds JSON")


def load_run(run_dir):
    """trace.csv, epochs.csv and summary.json of a run directory."""
    trace = pd.read_csv(run_dir / "trace.csv")
    epochs = pd.read_csv(run_dir / "epochs.csv")
    summary = json.loads((run_dir / "summary.json").read_text())
    # Every trace column is a number: t [s], w_L<k> and f_L<k> per link, p/v per body,
    # the invariants Px..KE (and qw..wz per body with output.trace_rotation).
    require_numeric(trace, trace.columns, "trace.csv")
    # So is every epochs.csv column (times, delays, bandwidth, cost, objectives).
    require_numeric(epochs, epochs.columns, "epochs.csv")
    require_no_json(epochs, "epochs.csv")
    return trace, epochs, summary


def load_sweep(sweep_dir):
    """sweep.csv of a sweep directory and the names of its axis columns."""
    sweep = pd.read_csv(sweep_dir / "sweep.csv")
    # Axis columns sit between `point` and `rep`/`seed` (see src/sweep/table.rs).
    cols = list(sweep.columns)
    end = cols.index("rep") if "rep" in cols else cols.index("seed")
    axes = cols[cols.index("point") + 1 : end]
    numeric = ["index", "seed", "diverged_at", "diverged_node", "mean_cost", "lost_frames",
               "bandwidth"]
    numeric += [c for c in cols if c.startswith(("tau_", "unpaired_mean_cost_"))]
    require_numeric(sweep, numeric, "sweep.csv")
    require_no_json(sweep, "sweep.csv")
    return sweep, axes


def main(argv):
    if len(argv) != 4:
        sys.exit(__doc__.split("\n\n")[1])
    run_dir, sweep_dir, out = (Path(a) for a in argv[1:])
    out.mkdir(parents=True, exist_ok=True)

    trace, epochs, summary = load_run(run_dir)
    print(f"{run_dir}: scenario {summary['scenario']}, {len(trace)} trace rows, "
          f"{len(epochs)} epochs, mean cost {epochs['cost'].mean():.4g} m")
    links = [c for c in ("w_L1", "w_L2") if c in trace.columns]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for c in links:
        ax.plot(trace["t"], trace[c], label=c[2:])
    ax.set_xlabel("t [s]")
    ax.set_ylabel("constraint violation w [m]")
    ax.set_title(f"{summary['scenario']}: constraint violation")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "constraints.png", dpi=100)
    plt.close(fig)

    sweep, axes = load_sweep(sweep_dir)
    axis = axes[0]
    print(f"{sweep_dir}: {len(sweep)} points, axes {axes}, "
          f"{(sweep['status'] == 'ok').sum()} ok")
    # Mean over repetitions and any axes past the second; one line per value of the
    # second axis, if there is one.
    keys = axes[:2]
    cost = sweep.groupby(keys, sort=False)["mean_cost"].mean().reset_index()
    fig, ax = plt.subplots(figsize=(6, 3.5))
    groups = cost.groupby(axes[1], sort=False) if len(axes) > 1 else [(None, cost)]
    for key, g in groups:
        x = g[axis] if is_numeric_dtype(g[axis]) else g[axis].astype(str)
        ax.plot(x, g["mean_cost"], marker="o",
                label=None if key is None else f"{axes[1]} = {key}")
    ax.set_xlabel(axis)
    if not is_numeric_dtype(cost[axis]):
        ax.tick_params(axis="x", labelrotation=60, labelsize=7)
    ax.set_ylabel("mean cost [m]")
    if len(axes) > 1:
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / "mean_cost.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out / 'constraints.png'} and {out / 'mean_cost.png'}")


if __name__ == "__main__":
    main(sys.argv)
