#!/usr/bin/env python3
"""Writes tdma4_slot_layouts.json, the slot-layout study on the 4-node TDMA scene.

Run from anywhere: `python3 scenarios/sweeps/make_tdma4_slot_layouts.py`. The sweep
file is what ships; this script only documents how its slot lists were built and
rewrites it identically.

Every layout gives each of the six (TDMA node, channel) pairs of the 4-node ring,
(1,tau1) (2,tau1) (4,tau1) (2,tau2) (3,tau2) (4,tau2), exactly one frame every 5 ms
(tau = 5 ms for every pair), so the bandwidth is the same and only the layout differs:
the order of the pairs, the cycle length (how often clocks are re-synced), the slot
length and guard (how much of a slot a frame leaves unused), and idle slots between
entries, and where the entries sit against the 1 ms integration steps (the `_off_step`
layouts start at 1.1 ms, so no frame starts on a step boundary). Axes: `layout` (whole
/network objects, applied first), then `drift` (/network/drift_ppm, added to the
layout's network), then `draw` (/seed: the same ten
seeds for every layout and drift, so layouts are compared on the same clock draws).
"""

import json
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))

# The 4-node ring's pairs, grouped by channel (the scheduler's own order) ...
BLOCKED = [(1, "tau1"), (2, "tau1"), (4, "tau1"), (2, "tau2"), (3, "tau2"), (4, "tau2")]
# ... and with the channels alternating.
INTERLEAVED = [(1, "tau1"), (2, "tau2"), (2, "tau1"), (3, "tau2"), (4, "tau1"), (4, "tau2")]

# 4 clients: sync slot + 5 static slots precede the dynamic part.
STATIC = 6


def entry(pair):
    if pair is None:
        return {"idle": True}
    node, channel = pair
    return {"node": node, "channel": channel}


def repeated(block, slot, cycle, tau=0.005):
    """`block` at dynamic offsets 0, tau/slot, 2·tau/slot, ... (cycle/tau copies), idle
    in between, so every pair is sent every tau, across the cycle boundary too."""
    per_tau = round(tau / slot)
    copies = round(cycle / tau)
    assert abs(per_tau * slot - tau) < 1e-12 and abs(copies * tau - cycle) < 1e-12
    entries = []
    for k in range(copies):
        entries += [entry(p) for p in block]
        if k + 1 < copies:
            entries += [entry(None)] * (per_tau - len(block))
    assert len(entries) <= round(cycle / slot) - STATIC, "list fits the dynamic part"
    return entries


def spaced(block):
    """`block` with an idle slot after every entry but the last."""
    out = []
    for i, p in enumerate(block):
        out.append(entry(p))
        if i + 1 < len(block):
            out.append(entry(None))
    return out


def network(slot_list, slot=1e-4, cycle=5e-3, guard=1e-5):
    # Everything but the layout as in tdma4_study_base.json (the thesis TDMA scene on
    # a 25 Mbit/s link, so the largest frame, 218 B, takes 69.76 µs of a slot). No
    # drift_ppm: the `drift` axis, applied after this one, adds it.
    return {
        "kind": "tdma",
        "slot": slot,
        "cycle": cycle,
        "guard": guard,
        "link_rate": 25e6,
        "propagation": 5e-07,
        "header_bytes": 26,
        "random_walk_ppm": 0.5,
        "sync_error": 2e-07,
        "jitter": {"kind": "exponential", "mean": 2e-05},
        "slot_list": slot_list,
    }


# Five idle slots first: the entries start at 1.1 ms (not 0.6 ms), so none starts on a
# 1 ms step boundary (slot 10, at 1.000 ms, does in the layouts above) and every frame
# arrives long before the next boundary.
OFF_STEP = [entry(None)] * 5


def spaced_off_step(block):
    """`block` with an idle slot after every entry, starting at 1.1 ms and skipping the
    slot at 2.0 ms: entries at 1.1, 1.3, 1.5, 1.7, 2.1 and 2.3 ms."""
    dyn = [5, 7, 9, 11, 15, 17]  # dynamic slot j is slot 6 + j, at (6 + j) · 0.1 ms
    out = [entry(None)] * (dyn[-1] + 1)
    for j, p in zip(dyn, block):
        out[j] = entry(p)
    return out


# The study's layouts, in the order of the `layout` axis (value index 0..9).
LAYOUTS = [
    ("interleaved_5ms", network([entry(p) for p in INTERLEAVED])),
    ("blocked_5ms", network([entry(p) for p in BLOCKED])),
    ("blocked_5ms_guard1us", network([entry(p) for p in BLOCKED], guard=1e-6)),
    # 64 slots of 78.125 µs: what a 1 µs guard allows (218 B + 1 µs fits in 70.76 µs).
    ("blocked_5ms_tight", network([entry(p) for p in BLOCKED], slot=7.8125e-5, guard=1e-6)),
    ("blocked_5ms_spaced", network(spaced(BLOCKED))),
    ("interleaved_20ms", network(repeated(INTERLEAVED, 1e-4, 0.02), cycle=0.02)),
    ("blocked_20ms", network(repeated(BLOCKED, 1e-4, 0.02), cycle=0.02)),
    ("interleaved_5ms_off_step", network(OFF_STEP + [entry(p) for p in INTERLEAVED])),
    ("blocked_5ms_off_step", network(OFF_STEP + [entry(p) for p in BLOCKED])),
    ("blocked_5ms_spaced_off_step", network(spaced_off_step(BLOCKED))),
]

SWEEP = {
    "name": "tdma4_slot_layouts",
    "base": "tdma4_study_base.json",
    "combine": "factorial",
    "axes": [
        {"name": "layout", "pointer": "/network", "values": [n for _, n in LAYOUTS],
         "labels": [f"{i} {name}" for i, (name, _) in enumerate(LAYOUTS)]},
        {"name": "drift", "pointer": "/network/drift_ppm",
         "values": [0, 300, 1000, 3000, 10000, 30000]},
        {"name": "draw", "pointer": "/seed", "values": list(range(1, 11))},
    ],
}

if __name__ == "__main__":
    path = os.path.join(HERE, "tdma4_slot_layouts.json")
    with open(path, "w") as f:
        text = json.dumps(SWEEP, indent=1)
        # One line per innermost object (slot-list entries, jitter) and number list.
        one_line = lambda m: " ".join(m.group(0).split())  # noqa: E731
        text = re.sub(r"\{[^{}\[\]]*\}", one_line, text)
        text = re.sub(r"\[[-+0-9.e,\s]*\]", one_line, text)
        f.write(text + "\n")
    for i, (name, _) in enumerate(LAYOUTS):
        print(f"layout {i}: {name}")
    print(f"wrote {path}")
