"""The package as a Python user expects it: Ctrl-C stops a call, stepping moves by h,
tables are exact and typed, a CoSim copies and pickles, errors are the built-in kinds,
warnings go through `warnings`, messages speak in the caller's arguments.

Each test here failed on the package before these conventions (issue: "Python users at
home"). No test asserts wall-clock time: a stopped call is told by the work it did not
do (a run's steps, a co-simulation's time, a sweep's points)."""

import copy
import json
import multiprocessing
import os
import pickle
import pty
import select
import signal
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import pandas as pd
import pytest

import dsmcosim

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO / "scenarios"
FIXED = SCENARIOS / "grid16_space_fixed.json"
# 4096 bodies: a slice of steps is 64 steps, and the whole scene runs for minutes.
LARGE = SCENARIOS / "grid64_tight.json"


def interrupted(body, timeout=300):
    """Runs `body` (Python source using `dsmcosim`, whose call under test follows a
    line printing "ready") in a child process, sends it SIGINT a second after "ready",
    and returns what the child printed after. The child prints the exception it got
    and what it can see of the work done."""
    script = "import dsmcosim, json, sys\n" + textwrap.dedent(body)
    child = subprocess.Popen(
        [sys.executable, "-c", script], cwd=REPO, stdout=subprocess.PIPE, text=True,
        stderr=subprocess.PIPE,
        # pytest may run with SIGINT ignored; the child gets Python's own handler.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert child.stdout.readline().strip() == "ready"
    ready, _, _ = select.select([child.stdout], [], [], 1.0)
    assert not ready, "the call ended before it could be interrupted"
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=timeout)
    assert child.returncode == 0, err
    return out


def test_ctrl_c_stops_a_run_and_raises_keyboard_interrupt(tmp_path):
    out = interrupted(f"""
        print("ready", flush=True)
        try:
            dsmcosim.run({str(LARGE)!r}, {str(tmp_path)!r}, duration=30.0)
            print("finished")
        except KeyboardInterrupt:
            summary = json.load(open({str(tmp_path / "summary.json")!r}))
            print("KeyboardInterrupt", summary["status"], summary["steps"])
    """)
    word, status, steps = out.split()
    assert (word, status) == ("KeyboardInterrupt", "interrupted"), out
    # Stopped within a few slices of 64 steps of the signal: far from 30 000 steps.
    assert 0 < int(steps) < 30000, out


def test_ctrl_c_stops_advance_where_the_co_simulation_can_go_on():
    out = interrupted(f"""
        sim = dsmcosim.CoSim({str(LARGE)!r}, duration=30.0)
        print("ready", flush=True)
        try:
            sim.advance(30.0)
            print("finished")
        except KeyboardInterrupt:
            now = sim.now
            sim.advance(now + 0.01)
            print("KeyboardInterrupt", now, sim.now)
    """)
    word, stopped, after = out.split()
    assert word == "KeyboardInterrupt", out
    assert 0 < float(stopped) < 30.0 and float(after) == pytest.approx(float(stopped) + 0.01)


def test_ctrl_c_stops_a_sweep_before_its_other_points(tmp_path):
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps({
        "name": "long", "base": str(LARGE), "overrides": {"/duration": 30.0},
        "axes": [{"name": "draw", "pointer": "/seed", "values": list(range(1, 9))}]}))
    out = interrupted(f"""
        print("ready", flush=True)
        try:
            dsmcosim.sweep({str(sweep)!r}, {str(tmp_path / "out")!r}, keep="summary")
            print("finished")
        except KeyboardInterrupt as e:
            print("KeyboardInterrupt")
    """)
    assert out.split() == ["KeyboardInterrupt"], out
    done = list((tmp_path / "out").glob("points/*/done.json"))
    assert len(done) < 8


def test_a_progress_callable_returning_false_stops_the_run(tmp_path):
    calls = []

    def stop_at_500(position, total, unit):
        calls.append(position)
        return position < 500

    ran = dsmcosim.run(FIXED, tmp_path, duration=10.0, progress=stop_at_500)
    assert ran.status == "interrupted" and ran.summary["status"] == "interrupted"
    assert ran.summary["steps"] < 10001
    assert len(ran.trace) < 10001
    # The next call runs: the stop was withdrawn.
    assert dsmcosim.run(FIXED, duration=1.0).status == "ok"


def test_advance_moves_to_t_on_the_step_grid_and_never_back():
    sim = dsmcosim.CoSim(FIXED, duration=1.0)
    sim.advance(0.5)
    assert sim.now == 0.5
    sim.advance(0.5145)
    assert sim.now == pytest.approx(0.515), "rounded up to the 1-ms grid"
    with pytest.raises(dsmcosim.InvalidScenarioError) as e:
        sim.advance(0.5145)
    assert e.value.field == "t"
    h, steps = 0.07, 0
    while not sim.finished:
        sim.advance(sim.now + h)
        steps += 1
    assert steps == 7 and sim.now == 1.0


def test_h_steps_give_the_command_lines_digest(tmp_path):
    """Advancing by h off the window boundaries changes nothing of the run."""
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    while not sim.finished:
        sim.advance(sim.now + 0.0333)
    cli = dsmcosim.run(FIXED, duration=2.0)
    assert sim.digest == cli.digest


def test_non_positive_periods_are_refused_at_the_call():
    sim = dsmcosim.CoSim(FIXED, duration=1.0)
    for bad in [0.0, -0.004, float("nan"), float("inf")]:
        with pytest.raises(dsmcosim.InvalidScenarioError) as e:
            sim.set_periods([bad, 0.005])
        assert e.value.field == "periods[0]", bad
    assert sim.schedule() == []


def test_every_float_is_exact_and_every_column_has_one_type(tmp_path):
    """The value the review saw misread (0.00639642385637425) is in this run's epochs;
    times are float64 even when every recorded time is whole."""
    stored = REPO / "results" / "grid16_space_cp_ds2" / "epochs.csv"
    epochs = dsmcosim.read_table(stored)
    text = stored.read_text().splitlines()
    header = text[0].split(",")
    assert any("0.00639642385637425" in line for line in text)
    for line, (_, row) in zip(text[1:], epochs.iterrows()):
        for name, cell in zip(header, line.split(",")):
            if cell in ("", "NaN"):
                assert pd.isna(row[name]), (name, cell, row[name])
            else:
                assert float(row[name]) == float(cell), (name, cell, row[name])
    ran = dsmcosim.run(SCENARIOS / "tdma4_space_fixed.json", tmp_path, duration=2.5)
    whole = dsmcosim.run(FIXED, duration=3.0, output__decimation=1000)
    assert list(whole.trace["t"]) == [0.0, 1.0, 2.0, 3.0]
    assert whole.trace["t"].dtype == "float64"
    assert ran.epochs["t_start"].dtype == ran.epochs["t_end"].dtype == "float64"
    assert whole.epochs["t_start"].dtype == "float64"
    assert epochs["measurements"].dtype == "Int64"
    assert ran.network["bytes"].dtype == "Int64" and ran.network["kind"].dtype == object


def test_a_copy_is_a_fork_and_a_cosim_pickles():
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    sim.set_periods([0.004, 0.006])
    sim.advance(1.0)
    shallow, deep = copy.copy(sim), copy.deepcopy(sim)
    shallow.advance(1.5)
    deep.advance(1.2)
    assert sim.now == 1.0, "advancing a copy leaves the original"
    restored = pickle.loads(pickle.dumps(sim))
    assert restored.now == 1.0 and restored.periods == sim.periods
    assert restored.schedule() == sim.schedule()
    restored.advance(2.0)
    sim.advance(2.0)
    assert restored.digest == sim.digest


def _finish(sim):
    sim.advance(sim.duration)
    return sim.digest


def test_a_cosim_goes_to_another_process_and_comes_back_the_same():
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    sim.advance(1.0)
    context = multiprocessing.get_context("spawn")
    with context.Pool(1) as pool:
        remote = pool.apply(_finish, (sim,))
    assert remote == _finish(sim)


def test_errors_are_the_built_in_kinds(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        dsmcosim.run(tmp_path / "missing.json")
    assert isinstance(e.value, dsmcosim.DsmcosimError) and e.value.errno == 2
    assert e.value.filename == str(tmp_path / "missing.json")
    with pytest.raises(ValueError) as e:
        dsmcosim.validate(FIXED, dt=-1.0)
    assert isinstance(e.value, dsmcosim.InvalidScenarioError) and e.value.field == "dt"
    with pytest.raises(dsmcosim.DivergedError) as e:
        dsmcosim.run(FIXED, tmp_path / "out", set={"/divergence": {"max_violation": 1e-6}})
    d = e.value
    assert isinstance(d, dsmcosim.SimulationError) and d.exit_code == 3
    assert d.time > 0 and d.node >= 0 and d.link is not None and d.link.startswith("L")
    assert f"link {d.link}" in str(d) and "|w|" in d.what


def test_warnings_go_through_warnings_and_bars_stay_away_unless_asked(tmp_path):
    with pytest.warns(dsmcosim.DsmcosimWarning, match="boundary layer"):
        dsmcosim.run(FIXED, duration=3.0, stabilizer__epsilon=1e-4)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dsmcosim.run(FIXED, duration=1.0, integrator="rk4")


def test_no_terminal_bar_without_progress():
    """On a terminal, a call of more than 2 s drew the crate's indicatif bar though
    progress=None; now nothing is written."""
    leader, follower = pty.openpty()
    script = (f"import dsmcosim; dsmcosim.CoSim({str(LARGE)!r}, duration=30.0)"
              ".advance(0.6); print('done')")
    child = subprocess.Popen([sys.executable, "-c", script], cwd=REPO,
                             stdout=subprocess.PIPE, stderr=follower, text=True)
    os.close(follower)
    out, _ = child.communicate(timeout=600)
    assert out.strip() == "done"
    written = b""
    while select.select([leader], [], [], 0.1)[0]:
        try:
            chunk = os.read(leader, 4096)
        except OSError:
            break
        if not chunk:
            break
        written += chunk
    os.close(leader)
    assert written == b"", written


def test_messages_name_python_arguments(tmp_path):
    with pytest.raises(dsmcosim.InvalidScenarioError) as e:
        dsmcosim.run(FIXED, channels__0__tau=-1.0)
    assert "channels__0__tau=-1.0" in str(e.value) and "--set" not in str(e.value)
    with pytest.raises(dsmcosim.InvalidScenarioError) as e:
        dsmcosim.validate(FIXED, set={"/channels/0/tau": -1.0})
    assert "set={'/channels/0/tau': -1.0}" in e.value.message
    dsmcosim.run(FIXED, tmp_path / "a", duration=1.0)
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.run(SCENARIOS / "grid16_time_fixed.json", tmp_path / "a", duration=1.0)
    assert "force=True" in str(e.value) and "--force" not in str(e.value)
    sweep = {"name": "s", "base": "grid16_space_fixed.json",
             "overrides": {"/duration": 0.2, "/measurement/period": 0.1},
             "axes": [{"name": "tau1", "pointer": "/channels/0/tau", "values": [0.004]}]}
    dsmcosim.sweep(sweep, tmp_path / "s", keep="summary", base_dir=SCENARIOS)
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.sweep(sweep, tmp_path / "s", keep="summary", base_dir=SCENARIOS)
    assert "resume=True" in str(e.value) and "--resume" not in str(e.value)


def test_tables_are_read_on_access_and_in_part(tmp_path):
    ran = dsmcosim.run(FIXED, tmp_path, duration=1.0)
    (tmp_path / "network.csv").write_text("not read unless asked")
    assert ran.digest and ran.summary["steps"] == 1000
    part = ran.table("trace", columns=["t", "w_L1"])
    assert list(part.columns) == ["t", "w_L1"] and len(part) == len(ran.trace)
    with pytest.raises(KeyError, match="w_L999"):
        ran.table("trace", columns=["w_L999"])
    unkept = dsmcosim.run(FIXED, duration=1.0)
    assert unkept.directory.is_dir() and unkept.trace.equals(ran.trace)
    where = unkept.directory
    del unkept
    assert not where.exists(), "a run with out=None keeps its files only while it lives"


def test_the_package_is_typed():
    root = Path(dsmcosim.__file__).parent
    assert (root / "py.typed").is_file() and (root / "_native.pyi").is_file()


def test_a_notebook_without_ipywidgets_gets_the_text_bar_and_no_warning(monkeypatch, capsys):
    tqdm = pytest.importorskip("tqdm")
    from dsmcosim import _api
    monkeypatch.setattr(_api, "_in_notebook", lambda: True)
    monkeypatch.setitem(sys.modules, "ipywidgets", None)  # import fails: not installed
    assert _api._tqdm() is tqdm.tqdm
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ran = dsmcosim.run(FIXED, duration=1.0, progress=True)
    assert ran.status == "ok" and "1000/1000" in capsys.readouterr().err


RESULTS = REPO / "results"


def test_load_reads_a_stored_run_and_a_stored_sweep():
    stored = dsmcosim.load(RESULTS / "grid16_space_cp_ds2")
    assert isinstance(stored, dsmcosim.Run)
    summary = json.loads((RESULTS / "grid16_space_cp_ds2" / "summary.json").read_text())
    assert stored.digest == summary["digest"] and stored.directory.is_dir()
    assert len(stored.epochs) == 30
    table = dsmcosim.load(RESULTS / "sweeps" / "dsm_size_cp")
    assert isinstance(table, pd.DataFrame)
    assert len(table) == len((RESULTS / "sweeps" / "dsm_size_cp" / "sweep.csv")
                             .read_text().splitlines()) - 1
    assert table["dsm_size"].dtype == "float64" and table["seed"].dtype == "UInt64"
    with pytest.raises(ValueError, match="neither a run"):
        dsmcosim.load(RESULTS)
    with pytest.raises(FileNotFoundError):
        dsmcosim.load(RESULTS / "no such run")


def test_a_run_plots_its_standard_figures(tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    fig = dsmcosim.load(RESULTS / "grid16_space_cp_ds2").plot()
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["Constraint violation", "Cost of each measurement window",
                      "Achieved period of each channel"]
    assert fig.axes[0].get_ylabel() == "max |w| [m]"
    assert fig.axes[-1].get_xlabel() == "simulated time [s]"
    assert [t.get_text() for t in fig.axes[2].get_legend().get_texts()] == ["tau1", "tau2"]
    fig.savefig(tmp_path / "run.svg")
    assert (tmp_path / "run.svg").stat().st_size > 0


BIN = Path(os.environ.get("DSMCOSIM_BIN", REPO / "target" / "release" / "dsmcosim"))


def small_sweep(tmp_path):
    """A 6-point sweep of the grid over two axes, and the command line's sweep.csv."""
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps({
        "name": "executor", "base": str(FIXED),
        "overrides": {"/duration": 1.0, "/measurement/period": 0.25},
        "axes": [{"name": "tau1", "pointer": "/channels/0/tau", "values": [0.002, 0.005, 0.01]},
                 {"name": "draw", "pointer": "/seed", "values": [1, 2]}]}))
    subprocess.run([str(BIN), "sweep", str(sweep), "--out", str(tmp_path / "cli"), "-q",
                    "--keep", "summary"], check=True, capture_output=True)
    return sweep, (tmp_path / "cli" / "sweep.csv").read_bytes()


def test_a_sweep_on_a_process_pool_writes_the_command_lines_table(tmp_path):
    from concurrent.futures import ProcessPoolExecutor
    sweep, cli = small_sweep(tmp_path)
    out = tmp_path / "pool"
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(2, mp_context=context) as pool:
        table = dsmcosim.sweep(sweep, out, keep="summary", executor=pool)
    assert (out / "sweep.csv").read_bytes() == cli
    assert len(table) == 6 and table["draw"].dtype == "Int64"
    # A rerun with resume runs no point again: each point's record is left as it was.
    stamps = {p: p.stat().st_mtime_ns for p in out.glob("points/*/done.json")}
    ran = []
    with context.Pool(2) as pool:
        dsmcosim.sweep(sweep, out, keep="summary", resume=True, executor=pool,
                       progress=lambda pos, total, unit: ran.append(total))
    assert ran == [] and stamps == {p: p.stat().st_mtime_ns for p in out.glob("points/*/done.json")}
    assert (out / "sweep.csv").read_bytes() == cli


def test_a_point_is_deterministic_and_runs_once(tmp_path):
    sweep, _ = small_sweep(tmp_path)
    out = tmp_path / "points"
    keys = dsmcosim._native.sweep_pending(str(sweep), str(out), [], "summary", False)
    spec = {"sweep": str(sweep), "out": str(out), "sets": [], "keep": "summary", "key": keys[0]}
    first = dsmcosim.point(pickle.loads(pickle.dumps(spec)))
    done = out / "points" / keys[0] / "done.json"
    stamp = done.stat().st_mtime_ns
    assert dsmcosim.point(spec) == first and done.stat().st_mtime_ns == stamp
    other = tmp_path / "again"
    dsmcosim._native.sweep_pending(str(sweep), str(other), [], "summary", False)
    assert dsmcosim.point({**spec, "out": str(other)}) == first


def test_a_sweep_on_a_local_dask_cluster_writes_the_command_lines_table(tmp_path):
    distributed = pytest.importorskip("distributed")
    sweep, cli = small_sweep(tmp_path)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        dsmcosim.sweep(sweep, tmp_path / "dask", keep="summary",
                       executor=client.get_executor())
    assert (tmp_path / "dask" / "sweep.csv").read_bytes() == cli


def test_a_sweep_on_a_ray_pool_writes_the_command_lines_table(tmp_path):
    # The module itself: a bare `ray` may be a leftover session directory on the path.
    Pool = pytest.importorskip("ray.util.multiprocessing").Pool
    sweep, cli = small_sweep(tmp_path)
    pool = Pool(processes=2, ray_address="local")
    try:
        dsmcosim.sweep(sweep, tmp_path / "ray", keep="summary", executor=pool)
    finally:
        pool.terminate()
        import ray
        ray.shutdown()
    assert (tmp_path / "ray" / "sweep.csv").read_bytes() == cli


def test_observe_gives_the_state_the_trace_records_at_now_and_changes_nothing(tmp_path):
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    sim.advance(1.0)
    seen = sim.observe()
    assert seen.time == 1.0 and sim.now == 1.0
    assert seen.positions.shape == (16, 3) and seen.rows[:2] == ["L1", "L2"]
    cli = dsmcosim.run(FIXED, tmp_path, duration=2.0)
    row = cli.trace[cli.trace["t"] == 1.0].iloc[0]
    assert [row[f"w_{r}"] for r in seen.rows] == list(seen.w)
    assert [row[f"f_{r}"] for r in seen.rows] == list(seen.f)
    for k, body in enumerate(seen.bodies):
        if f"px_B{body}" in row:
            assert [row[f"{a}_B{body}"] for a in ("px", "py", "pz")] == list(seen.positions[k])
            assert [row[f"{a}_B{body}"] for a in ("vx", "vy", "vz")] == list(seen.velocities[k])
    assert seen.max_w == max(abs(seen.w))
    sim.advance(2.0)
    assert sim.digest == cli.digest, "observing changed nothing"
    end = sim.observe()
    assert end.time == 2.0 and list(end.w) == [cli.trace.iloc[-1][f"w_{r}"] for r in end.rows]


def test_observe_reads_an_fmus_outputs(tmp_path):
    fmu = SCENARIOS / "fmu" / "msd.fmu"
    if not fmu.is_file():
        pytest.skip("the test FMUs are built by `cargo run --release --example build_fmus "
                    "-- scenarios/fmu`")
    sim = dsmcosim.CoSim(SCENARIOS / "fmu_pd_loop.json", duration=1.0)
    sim.advance(0.5)
    seen = sim.observe()
    cli = dsmcosim.run(SCENARIOS / "fmu_pd_loop.json", tmp_path, duration=1.0)
    row = cli.trace[cli.trace["t"] == 0.5].iloc[0]
    assert seen.signals and all(row[name] == value for name, value in seen.signals.items())


def test_fmu_outputs_of_every_type_read_as_their_python_types_in_observe_and_the_trace(tmp_path):
    fmu = SCENARIOS / "fmu" / "types3.fmu"
    if not fmu.is_file():
        pytest.skip("the test FMUs are built by `cargo run --release --example build_fmus "
                    "-- scenarios/fmu`")
    scene = {"name": "types3", "seed": 1, "duration": 1.0, "dt": 0.1,
             "output": {"decimation": 1},
             "fmus": [{"name": "u", "path": str(fmu),
                       "start": {"f32_p": 0.3, "str_p": "NaN", "i64_p": 9007199254740993}}]}
    sim = dsmcosim.CoSim(scene)
    sim.advance(0.7)
    seen = sim.observe()
    cli = dsmcosim.run(scene, tmp_path / "out")
    row = cli.trace[cli.trace["t"] == 0.7].iloc[0]
    assert len(seen.signals) == 19  # 14 scalars, y[1..3], z[1..2]
    assert all(row[name] == value for name, value in seen.signals.items())
    # Each in its type: 2^53 + 1 + 7 exact, a UInt64 near 2^64, text, bytes, a Float32.
    assert seen.signals["u.i64_out"] == 9007199254741000 == row["u.i64_out"]
    assert seen.signals["u.u64_out"] == 2**64 - 1 - 7 == row["u.u64_out"]
    assert seen.signals["u.str_out"] == "NaN #7" == row["u.str_out"]
    assert seen.signals["u.bin_out"] == bytes([0, 255, 7]) == row["u.bin_out"]
    assert seen.signals["u.bool_out"] is True
    import numpy as np
    assert seen.signals["u.f32_out"] == float(np.float32(0.3) * np.float32(7))


def test_an_fmu_output_that_is_not_a_number_is_a_divergence_naming_it(tmp_path):
    fmu = SCENARIOS / "fmu" / "quirks.fmu"
    if not fmu.is_file():
        pytest.skip("the test FMUs are built by `cargo run --release --example build_fmus "
                    "-- scenarios/fmu`")
    scene = {"name": "quirks", "seed": 1, "duration": 0.2, "dt": 0.001,
             "fmus": [{"name": "q", "path": str(fmu), "start": {"nan_at": 0.05, "F": 1.0},
                       "trace": ["x", "v"]}]}
    with pytest.raises(dsmcosim.DivergedError) as caught:
        dsmcosim.run(scene, tmp_path / "out")
    e = caught.value
    assert e.fmu_output == "q.x" and e.link is None and e.body is None, vars(e)
    assert 0.05 <= e.time <= 0.06 and e.exit_code == 3, vars(e)


def test_observe_lists_the_last_delivery_on_every_route():
    sim = dsmcosim.CoSim(FIXED, duration=1.0)
    sim.advance(0.1)
    d = sim.observe().deliveries
    assert set(d["channel"]) == {"tau1", "tau2"} and set(d["kind"]) <= {"state", "force"}
    assert (d["sent"] <= d["delivered"]).all() and (d["delivered"] <= 0.1).all()
    assert (d["age"] >= 0).all() and (d["age"] <= 0.1).all()
    assert len(d) == len(d.drop_duplicates(["channel", "from_node", "to_node", "kind",
                                            "element"]))
    assert sim.fork().observe().deliveries.equals(d)


def test_a_jupyter_kernel_interrupt_stops_a_run(tmp_path):
    """A notebook's "Interrupt kernel": a real IPython kernel runs a long run in a cell;
    the interrupt ends the cell with KeyboardInterrupt, and the kernel runs the next
    cell."""
    manager_module = pytest.importorskip("jupyter_client.manager")
    pytest.importorskip("ipykernel")
    import queue
    manager, client = manager_module.start_new_kernel(kernel_name="python3", cwd=str(REPO))
    try:
        client.execute("import dsmcosim")
        client.get_shell_msg(timeout=60)
        cell = client.execute(
            f"dsmcosim.run({str(LARGE)!r}, {str(tmp_path)!r}, duration=30.0)")
        while True:  # the cell is running once the kernel says busy
            msg = client.get_iopub_msg(timeout=60)
            if msg["msg_type"] == "status" and msg["content"]["execution_state"] == "busy" \
                    and msg["parent_header"].get("msg_id") == cell:
                break
        with pytest.raises(queue.Empty):
            client.get_shell_msg(timeout=1.0)  # still running a second later
        manager.interrupt_kernel()
        reply = client.get_shell_msg(timeout=120)
        assert reply["parent_header"]["msg_id"] == cell
        assert reply["content"]["status"] == "error"
        assert reply["content"]["ename"] == "KeyboardInterrupt"
        summary = json.loads((tmp_path / "summary.json").read_text())
        assert summary["status"] == "interrupted" and summary["steps"] < 30000
        client.execute("x = 1 + 1")
        assert client.get_shell_msg(timeout=60)["content"]["status"] == "ok"
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)
