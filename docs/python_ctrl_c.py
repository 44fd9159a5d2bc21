"""How long a Python call takes to stop after Ctrl-C (docs/python.md, "Ctrl-C").

    python docs/python_ctrl_c.py          # from the checkout, the package installed

For each of `run`, `CoSim.advance` and `sweep` on scenarios/grid64_tight.json (4096
bodies, minutes of work), a child process starts the call, gets SIGINT three seconds
in, and the time from the signal to the child's exit is printed with what the child
saw (KeyboardInterrupt, the run's status, where the co-simulation stopped)."""

import json
import signal
import subprocess
import sys
import tempfile
import textwrap
import time

CALLS = {
    "run": """
        try:
            dsmcosim.run("scenarios/grid64_tight.json", OUT, force=True)
        except KeyboardInterrupt:
            print("KeyboardInterrupt, status", json.load(open(OUT + "/summary.json"))["status"])
    """,
    "advance": """
        sim = dsmcosim.CoSim("scenarios/grid64_tight.json")
        try:
            sim.advance(sim.duration)
        except KeyboardInterrupt:
            print("KeyboardInterrupt at now =", sim.now, "s")
    """,
    "sweep": """
        try:
            dsmcosim.sweep("scenarios/sweeps/tdma4_slot_layouts.json", OUT, keep="summary")
        except KeyboardInterrupt:
            print("KeyboardInterrupt")
    """,
}

for name, body in CALLS.items():
    with tempfile.TemporaryDirectory() as out:
        script = (f"import dsmcosim, json\nOUT = {out + '/out'!r}\nprint('ready', flush=True)\n"
                  + textwrap.dedent(body))
        child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                                 text=True,
                                 preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        assert child.stdout.readline().strip() == "ready"
        time.sleep(3)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        said = child.communicate(timeout=600)[0].strip()
        print(f"{name}: exited {time.monotonic() - sent:.2f} s after SIGINT: {said}")
