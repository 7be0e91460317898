"""CLI: simulate, inspect, clean and simulate-bench end to end on small runs."""

from __future__ import annotations

import json

from click.testing import CliRunner

from seadesign.cli import main
from seadesign.data import read_bench, read_recording


def test_simulate_inspect_clean_bench(tmp_path, spring_file):
    run = CliRunner().invoke
    out = tmp_path / "sim.csv"
    r = run(main, ["simulate", "--spring", str(spring_file), "--ground", "--seed", "2", "--rate-hz", "50",
                   "--trial-duration-s", "2", "--effect", "hysteresis:torque_Nm=0.2", "-o", str(out)])
    assert r.exit_code == 0, r.output
    df = read_recording(out)
    assert len(df) == 18 * 100 and "hysteresis" in df.attrs["metadata"]["effects_enabled"]
    r = run(main, ["data", "inspect", str(out), "--plot", str(tmp_path / "p.png"), "--json", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "p.png").stat().st_size > 0 and json.loads((tmp_path / "r.json").read_text())["rows"] == 1800
    r = run(main, ["data", "clean", str(out), "-o", str(tmp_path / "c.csv"), "--positive"])
    assert r.exit_code == 0, r.output
    r = run(main, ["simulate-bench", "--spring", str(spring_file), "--duration-s", "10", "--effect",
                   "dead_band:width_rad=0.02", "-o", str(tmp_path / "b.csv")])
    assert r.exit_code == 0, r.output
    assert len(read_bench(tmp_path / "b.csv")) == 1000
    r = run(main, ["simulate", "--spring", str(spring_file), "--effect", "nope", "-o", str(tmp_path / "x.csv")])
    assert r.exit_code == 2 and "no effect named 'nope'" in r.output


def test_the_api_simulates_what_the_commands_write(tmp_path, spring_file, spring_dict):
    """`sd.simulate` and `sd.simulate_bench` give the tables the commands write (read back from their files),
    from the spring's file or its content."""
    import numpy as np

    import seadesign as sd

    out = tmp_path / "walk.csv"
    r = CliRunner().invoke(main, ["simulate", "--spring", str(spring_file), "--ground", "--seed", "3", "--rate-hz",
                                  "50", "--trial-duration-s", "1", "--effect", "hysteresis:torque_Nm=0.2", "-o", str(out)])
    assert r.exit_code == 0, r.output
    written = read_recording(out)
    table, meta = sd.simulate(spring_dict, ground=True, seed=3, rate_hz=50.0, trial_duration_s=1.0,
                              effects=("hysteresis:torque_Nm=0.2",))
    assert len(table) == len(written) == 18 * 50 and "spring_file" not in meta
    columns = [c for c in written.columns if c in table.columns and np.issubdtype(written[c].dtype, np.number)]
    assert {"l_hall_pos", "r_knee_pos", "l_knee_eff"} <= set(columns)
    np.testing.assert_allclose(table[columns].to_numpy(float), written[columns].to_numpy(float), rtol=1e-9, atol=1e-9)
    assert meta["effects_enabled"] == written.attrs["metadata"]["effects_enabled"]

    out = tmp_path / "bench.csv"
    r = CliRunner().invoke(main, ["simulate-bench", "--spring", str(spring_file), "--profile", "ramp", "--duration-s",
                                  "4", "--seed", "1", "-o", str(out)])
    assert r.exit_code == 0, r.output
    table, meta = sd.simulate_bench(spring_file, profile="ramp", duration_s=4.0, seed=1)
    written = read_bench(out)
    np.testing.assert_allclose(table[["torque_Nm", "deflection_rad"]].to_numpy(), written[["torque_Nm", "deflection_rad"]]
                               .to_numpy(), rtol=1e-9, atol=1e-12)
    assert meta["spring_file"] == str(spring_file) == written.attrs["metadata"]["spring_file"]


def test_the_api_inspects_and_cleans_what_the_commands_write(tmp_path, spring_file):
    """`sd.inspect_recording` gives the report `data inspect --json` writes, and `sd.clean_recording` the table
    `data clean` writes (read back from the files)."""
    import numpy as np
    import pandas as pd

    import seadesign as sd

    run = CliRunner().invoke
    out = tmp_path / "sim.csv"
    r = run(main, ["simulate", "--spring", str(spring_file), "--ground", "--seed", "4", "--rate-hz", "50",
                   "--trial-duration-s", "1", "-o", str(out)])
    assert r.exit_code == 0, r.output
    r = run(main, ["data", "inspect", str(out), "--step-threshold", "0.2", "--plot", str(tmp_path / "p.png"),
                   "--json", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    inspection = sd.inspect_recording(out, sd.Thresholds(step_threshold=0.2))
    assert json.loads(json.dumps(inspection.report.to_dict())) == json.loads((tmp_path / "r.json").read_text())
    assert inspection.report.format() in r.output
    assert inspection.plot(tmp_path / "api.png").stat().st_size > 0

    r = run(main, ["data", "clean", str(out), "-o", str(tmp_path / "c.csv"), "--positive", "--no-normalise"])
    assert r.exit_code == 0, r.output
    result = sd.clean_recording(out, positive=True, normalise=False)
    written = pd.read_csv(tmp_path / "c.csv")
    assert list(written.columns) == list(result.table.columns) and len(written) == len(result.table) > 0
    numeric = [c for c in written.columns if np.issubdtype(written[c].dtype, np.number)]
    np.testing.assert_allclose(result.table[numeric].to_numpy(float), written[numeric].to_numpy(float), rtol=1e-12)
    assert result.format() in r.output
