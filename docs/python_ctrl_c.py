"""How long a Python call takes to stop after Ctrl-C (docs/python.md, "Ctrl-C").

    python docs/python_ctrl_c.py          # from the checkout, the package installed

For each of `run`, `CoSim.advance` and `sweep` on scenarios/grid64_tight.json (4096
bodies, minutes of work), a child process starts the call, gets SIGINT three seconds
in, and the time from the signal to the child's exit is printed with what the child
saw (KeyboardInterrupt, the run's status, where the co-simulation stopped). Last, a
`run` on a pseudo-terminal gets Ctrl-C typed into it, as at a shell."""

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

# The same through a terminal: `run` in a child on a pseudo-terminal, and Ctrl-C typed
# into it (byte 0x03, which the terminal's line discipline turns into SIGINT for the
# foreground process), as a user at a shell would.
import os
import pty
import select

pid, fd = pty.fork()
if pid == 0:
    os.execv(sys.executable, [sys.executable, "-c", textwrap.dedent("""
        import dsmcosim, json, tempfile
        out = tempfile.mkdtemp() + "/out"
        print("ready", flush=True)
        try:
            dsmcosim.run("scenarios/grid64_tight.json", out)
        except KeyboardInterrupt:
            print("KeyboardInterrupt, status", json.load(open(out + "/summary.json"))["status"])
    """)])
seen = b""
while b"ready" not in seen:
    seen += os.read(fd, 1024)
time.sleep(3)
typed = time.monotonic()
os.write(fd, b"\x03")
said = b""
while select.select([fd], [], [], 600)[0]:
    try:
        chunk = os.read(fd, 4096)
    except OSError:  # the child closed the terminal
        break
    if not chunk:
        break
    said += chunk
os.waitpid(pid, 0)
text = said.decode(errors="replace").replace("^C", "").strip()
print(f"run on a terminal: exited {time.monotonic() - typed:.2f} s after Ctrl-C: {text}")
