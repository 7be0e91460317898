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
