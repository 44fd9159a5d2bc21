"""The Python package against the command line and the files a run writes.

Run from the checkout after `pip install .` (CI does, in a fresh venv):
`python -m pytest python/tests`. DSMCOSIM_BIN names the command-line binary to compare
with (default: target/release/dsmcosim of this checkout).
"""

import csv
import io
import json
import math
import os
import subprocess
import threading
from pathlib import Path

import pandas as pd
import pytest

import dsmcosim

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO / "scenarios"
BIN = Path(os.environ.get("DSMCOSIM_BIN", REPO / "target" / "release" / "dsmcosim"))


def cli_run(scenario, out, *sets):
    """Runs the command line on `scenario` with `--set` strings; its summary.json."""
    args = [str(BIN), "run", str(scenario), "--out", str(out), "-q"]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True, capture_output=True)
    return json.loads((Path(out) / "summary.json").read_text())


def test_a_run_gives_the_command_lines_digest_and_files(tmp_path):
    scenario = SCENARIOS / "tdma4_space_fixed.json"
    ran = dsmcosim.run(scenario, tmp_path / "py", duration=2.0)
    cli = cli_run(scenario, tmp_path / "cli", "/duration=2.0")
    assert ran.digest == cli["digest"]
    assert ran.summary["steps"] == cli["steps"] == 2000
    for name in ["trace.csv", "epochs.csv", "network.csv", "scenario.json"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_every_dataframe_round_trips_its_csv_file(tmp_path):
    """Each DataFrame holds exactly the file's values: every cell, parsed from the text
    with the standard library, equals the DataFrame's to the bit (the sign of a zero
    included; an empty cell is NaN), and each column is typed."""
    ran = dsmcosim.run(SCENARIOS / "tdma4_space_fixed.json", tmp_path, duration=2.0)
    for attr, name in [("trace", "trace.csv"), ("epochs", "epochs.csv"),
                       ("network", "network.csv")]:
        df = getattr(ran, attr)
        rows = list(csv.reader(io.StringIO((tmp_path / name).read_text())))
        header, rows = rows[0], rows[1:]
        assert list(df.columns) == header, name
        assert len(df) == len(rows) > 0, name
        for j, col in enumerate(header):
            kind = df[col].dtype.kind
            assert kind in "fiuO", (name, col, df[col].dtype)
            for i, row in enumerate(rows):
                cell, value = row[j], df[col].iloc[i]
                if cell == "":
                    assert pd.isna(value), (name, col, i)
                elif kind == "O":
                    assert value == cell, (name, col, i)
                else:
                    x = float(cell)
                    assert value == x and math.copysign(1, value) == math.copysign(1, x), \
                        (name, col, i, cell, value)
    assert ran.trace["t"].dtype.kind == "f" and ran.trace["t"].iloc[0] == 0.0


def test_a_dict_scenario_and_keyword_overrides_match_the_file_and_set(tmp_path):
    doc = json.loads((SCENARIOS / "grid16_space_fixed.json").read_text())
    doc["duration"] = 2.0
    doc["channels"][0]["tau"] = 0.004
    from_dict = dsmcosim.run(doc)
    from_file = dsmcosim.run(SCENARIOS / "grid16_space_fixed.json", duration=2.0,
                             channels__0__tau=0.004)
    by_pointer = dsmcosim.run(SCENARIOS / "grid16_space_fixed.json",
                              set={"/duration": 2.0, "/channels/0/tau": 0.004})
    assert from_dict.digest == from_file.digest == by_pointer.digest
    assert from_dict.directory.name.startswith("dsmcosim-run-"), "a temporary directory"
    other = dsmcosim.run(SCENARIOS / "grid16_space_fixed.json", duration=2.0)
    assert other.digest != from_dict.digest, "the override changed the run"


def test_bad_input_raises_naming_the_field_and_writes_nothing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.run(SCENARIOS / "grid16_space_fixed.json", out, channels__0__tau=-1.0)
    assert e.value.field == "channels[0].tau"
    assert e.value.exit_code == 2
    assert "channels__0__tau=-1.0" in e.value.message
    assert not out.exists()
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.validate({"name": "x", "seed": 1, "duration": 1.0, "dt": -0.001,
                           "model": {"grid": {"rows": 2, "cols": 2, "spacing": 1.0,
                                              "mass": 1.0, "size": 0.1}}})
    assert e.value.field == "dt"
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.run(SCENARIOS / "grid16_space_fixed.json", duraton=1.0)
    assert "duraton" in str(e.value)


def test_a_diverged_run_raises_with_exit_code_3_and_keeps_its_outputs(tmp_path):
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.run(SCENARIOS / "grid16_space_fixed.json", tmp_path,
                     set={"/divergence": {"max_violation": 1e-6}})
    assert e.value.exit_code == 3
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] != "ok"


def test_validate_returns_the_plan(tmp_path):
    plan = dsmcosim.validate(SCENARIOS / "tdma4_space_fixed.json")
    cli = tmp_path / "plan.json"
    subprocess.run([str(BIN), "validate", str(SCENARIOS / "tdma4_space_fixed.json"),
                    "--json", str(cli), "-q"], check=True, capture_output=True)
    assert plan == json.loads(cli.read_text())


def test_a_sweep_returns_its_table(tmp_path):
    sweep_file = tmp_path / "sweep.json"
    sweep_file.write_text(json.dumps({
        "name": "tiny", "base": str(SCENARIOS / "grid16_space_fixed.json"),
        "overrides": {"/duration": 2.0},
        "axes": [{"name": "tau1", "pointer": "/channels/0/tau",
                  "values": [0.002, 0.005, 0.01]}]}))
    table = dsmcosim.sweep(sweep_file, tmp_path / "out", keep="summary")
    assert list(table["tau1"]) == [0.002, 0.005, 0.01]
    assert (table["status"] == "ok").all()
    assert table.equals(dsmcosim.read_table(tmp_path / "out" / "sweep.csv",
                                            sweep_axes={"tau1": "float64"}))
    assert table["seed"].dtype == "UInt64" and table["index"].dtype == "Int64"
    # The middle point is the shipped scene at 2 s.
    assert table["digest"][1] == dsmcosim.run(SCENARIOS / "grid16_space_fixed.json",
                                              duration=2.0).digest


def test_runs_on_threads_give_the_same_digests(tmp_path):
    """The GIL is released during a run: two Python threads run at once, and each
    gives the digest it gives alone."""
    scenario = SCENARIOS / "grid16_space_fixed.json"
    alone = dsmcosim.run(scenario, duration=2.0).digest
    digests = [None, None]

    def work(k):
        digests[k] = dsmcosim.run(scenario, tmp_path / str(k), duration=2.0).digest

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=600)
    assert digests == [alone, alone]


FIXED = SCENARIOS / "grid16_space_fixed.json"


def test_a_steered_run_that_keeps_its_periods_gives_the_command_lines_digest(tmp_path):
    sim = dsmcosim.CoSim(FIXED, duration=3.0)
    assert sim.channels == ["tau1", "tau2"] and sim.periods == [0.005, 0.005]
    costs = []
    while not sim.finished:
        sim.advance(sim.now + 1.0)
        costs.append(sim.window_cost())
    cli = cli_run(FIXED, tmp_path, "/duration=3.0")
    assert sim.digest == cli["digest"]
    epochs = dsmcosim.read_table(tmp_path / "epochs.csv")
    assert [c[0] for c in costs] == [1.0, 2.0, 3.0]
    assert [c[1] for c in costs] == list(epochs["cost"]), "the windows the CLI measured"


def test_periods_set_at_the_start_give_the_digest_of_the_file_holding_them(tmp_path):
    """A Python controller's decision is the same run as the scenario that holds it:
    setting (4, 6) ms at t = 0 gives the digest of the file with those channel taus."""
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    assert sim.set_periods([0.004, 0.006]) == [0.004, 0.006]
    sim.advance(2.0)
    cli = cli_run(FIXED, tmp_path, "/duration=2.0", "/channels/0/tau=0.004",
                  "/channels/1/tau=0.006")
    assert sim.digest == cli["digest"]


def test_same_decisions_give_the_same_digest_and_other_decisions_another():
    def steered(schedule):
        sim = dsmcosim.CoSim(FIXED, duration=3.0)
        for periods in schedule:
            sim.set_periods(periods)
            sim.advance(sim.now + 1.0)
        return sim.digest

    a = [[0.005, 0.005], [0.003, 0.008], [0.0045, 0.0055]]
    assert steered(a) == steered(a)
    assert steered(a) != steered([[0.005, 0.005], [0.008, 0.003], [0.0045, 0.0055]])


def test_a_fork_leaves_the_run_it_came_from_untouched():
    plain = dsmcosim.CoSim(FIXED, duration=2.0)
    plain.advance(2.0)
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    sim.advance(1.0)
    trial = sim.fork()
    trial.set_periods([0.02, 0.02])
    trial.advance(2.0)
    sim.advance(2.0)
    assert sim.digest == plain.digest
    assert trial.digest != sim.digest
    assert trial.window_cost() != sim.window_cost()


def test_a_checkpoint_resumes_to_the_same_digest(tmp_path):
    sim = dsmcosim.CoSim(FIXED, duration=3.0)
    sim.set_periods([0.004, 0.007])
    sim.advance(1.0)
    path = sim.checkpoint(tmp_path)
    sim.advance(3.0)
    resumed = dsmcosim.CoSim.resume(path)
    assert resumed.now == 1.0 and resumed.periods == [0.004, 0.007]
    resumed.advance(3.0)
    assert resumed.digest == sim.digest


def test_steering_errors_name_what_is_wrong():
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        sim.set_periods([0.005])
    assert e.value.field == "periods"
    sim.advance(1.0)
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        sim.advance(0.5)
    assert e.value.field == "t"
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.CoSim(SCENARIOS / "grid16_space_cp.json")
    assert e.value.field == "controller"
    # A huge time is repeated in a short form, not with its 301 digits.
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        sim.advance(-1e300)
    assert "(got -1e300)" in str(e.value), str(e.value)


def test_a_mid_run_schedule_replays_through_the_cli(tmp_path):
    """The issue's "same decisions => same digest as the equivalent fixed schedule run
    through the command line", with decisions made mid-run: the scenario with
    `CoSim.schedule()` as its `schedule` gives the steered run's digest."""
    sim = dsmcosim.CoSim(FIXED, duration=4.0)
    for periods in [[0.005, 0.005], [0.003, 0.008], [0.0045, 0.0055], [0.009, 0.002]]:
        sim.set_periods(periods)
        sim.advance(sim.now + 1.0)
    schedule = sim.schedule()
    assert [e["at"] for e in schedule] == [0.0, 1.0, 2.0, 3.0]
    doc = json.loads(FIXED.read_text())
    doc["duration"] = 4.0
    doc["schedule"] = schedule
    scenario = tmp_path / "scheduled.json"
    scenario.write_text(json.dumps(doc))
    cli = cli_run(scenario, tmp_path / "cli")
    assert sim.digest == cli["digest"]
    epochs = pd.read_csv(tmp_path / "cli" / "epochs.csv")
    assert list(epochs["tau_tau1_requested"]) == [0.005, 0.003, 0.0045, 0.009]
    # Without the schedule the command line's run is another.
    assert cli_run(FIXED, tmp_path / "plain", "/duration=4.0")["digest"] != sim.digest


def test_a_schedule_refuses_decisions_it_cannot_hold():
    sim = dsmcosim.CoSim(FIXED, duration=2.0)
    sim.advance(0.5)
    sim.set_periods([0.004, 0.006])
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        sim.schedule()
    assert e.value.field == "decisions[0]" and "window boundaries" in e.value.message
    doc = json.loads(FIXED.read_text())
    doc["schedule"] = [{"at": 0, "tau": [0.004, 0.006]}]
    with pytest.raises(dsmcosim.DsmcosimError) as e:
        dsmcosim.CoSim(doc)
    assert e.value.field == "schedule"


def test_progress_reports_every_step_slice_and_every_sweep_point(tmp_path):
    seen = []
    dsmcosim.run(FIXED, duration=2.0, progress=lambda pos, total, unit: seen.append((pos, total, unit)))
    assert seen and all(unit == "steps" and total == 2000 for _, total, unit in seen)
    positions = [pos for pos, _, _ in seen]
    assert positions == sorted(positions) and positions[-1] == 2000

    windows = []
    dsmcosim.run(SCENARIOS / "grid16_space_cp.json", duration=3.0,
                 set={"/controller/surface_window": 1.0, "/controller/landscape": False,
                      "/controller/baselines": []},
                 progress=lambda pos, total, unit: windows.append((pos, total, unit)))
    assert windows[-1] == (3, 3, "windows")

    points = []
    sweep = {"name": "tiny", "base": "grid16_space_fixed.json",
             "overrides": {"/duration": 1.0},
             "axes": [{"name": "tau1", "pointer": "/channels/0/tau", "values": [0.002, 0.005]}]}
    table = dsmcosim.sweep(sweep, tmp_path / "out", keep="summary", base_dir=SCENARIOS,
                           progress=lambda pos, total, unit: points.append((pos, total, unit)))
    assert list(table["tau1"]) == [0.002, 0.005]
    assert points[-1] == (2, 2, "points")


def test_progress_true_draws_tqdm_bars_and_a_raising_callback_raises(capsys):
    pytest.importorskip("tqdm")
    ran = dsmcosim.run(FIXED, duration=2.0, progress=True)
    assert ran.summary["steps"] == 2000
    assert "2000/2000" in capsys.readouterr().err

    def broken(pos, total, unit):
        raise RuntimeError("bar broke")

    with pytest.raises(RuntimeError, match="bar broke"):
        dsmcosim.run(FIXED, duration=1.0, progress=broken)
