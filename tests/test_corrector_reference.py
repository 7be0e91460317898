"""The reference network, the reference-window feed-forward trained on ILC labels: the bundle; the simulator check;
and the closed-loop comparison of the reference network with the default, the closed-loop policy fine-tuning it, in
every case of the goal."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from click.testing import CliRunner
from conftest import thesis_spring

from seadesign.corrector.closedloop import run_closed_loop
from seadesign.corrector.export import NumpyCorrector, load_numpy, load_torchscript, numpy_arrays
from seadesign.corrector.goal import case_table, goal_cases, goal_table, verdict, winner
from seadesign.corrector.ilc import ILCSettings
from seadesign.corrector.imitation import ImitationSettings, label_arrays
from seadesign.corrector.runtime import FeedForward, HallPI, NoCorrection, ReferenceFeedForward
from seadesign.corrector.workflow import evaluate_bundles, load_corrector, train_reference_bundle
from seadesign.design.spring import write_spring
from seadesign.twin import Trial, thesis_protocol

SMALL = ImitationSettings(speeds=(0.075, 0.15), conditions=("hanging",), k_scales=(1.0,), trial_s=6.0,
                          ilc=ILCSettings(max_iterations=40))


def test_reference_bundle_records_its_simulator_and_runs_as_trained(tmp_path):
    """meta.json carries the window, k, the control rate and the simulator; the loaded bundle (NumPy path)
    drives the knee exactly as the network in memory; TorchScript and NumPy agree on the label inputs."""
    spring = thesis_spring()
    path = write_spring(spring, tmp_path / "spring.json")
    bundle, result, checks = train_reference_bundle(path, tmp_path / "ref", SMALL)
    assert checks == [] and meta_check(bundle) == []
    meta = json.loads((bundle / "meta.json").read_text())
    assert meta["model"] == "reference" and meta["reference"] == {"past": 5, "preview": 10}
    assert meta["k_Nm_per_rad"] == spring["k_Nm_per_rad"] and meta["control_rate_hz"] == 100.0
    assert meta["simulator"]["config"]["p_gain_Nm_per_rad"] == 60.0 and meta["simulator"]["conditions"] == ["hanging"]
    assert meta["input_units"][meta["inputs"].index("k_Nm_per_rad")] == "Nm/rad"
    assert meta["input_units"][meta["inputs"].index("load_share")].startswith("1")
    X, _, _ = label_arrays(result.labels, SMALL.window)
    with torch.no_grad():
        ts = load_torchscript(bundle)(torch.as_tensor(X[:500], dtype=torch.float32)).numpy()
    np.testing.assert_allclose(ts, load_numpy(bundle)(X[:500]), atol=1e-6)
    corrector, _ = load_corrector(bundle)
    trials = [Trial("back", 0.1, 4.0)]
    a = run_closed_loop(corrector, spring, trials)
    mem = ReferenceFeedForward(NumpyCorrector(numpy_arrays(result.training.net)), SMALL.window, spring["k_Nm_per_rad"])
    b = run_closed_loop(mem, spring, trials)
    np.testing.assert_array_equal(a.command, b.command)
    # evaluate without recordings: closed loop only, with the stability verdict (no feedback: L = 0, margin 1)
    res = evaluate_bundles([bundle], [], tmp_path / "eval", closed_loop=("hanging",), trial_s=3.0)
    assert "open_loop" not in res and res["settings"]["not_judged_open_loop"] == ["reference-ilc"]
    rows = {r["candidate"]: r for r in res["closed_loop"]}
    assert set(rows) == {"none", "pi", "feedforward", "reference-ilc"}
    assert rows["reference-ilc"]["stable"] and rows["reference-ilc"]["modulus_margin"] == 1.0
    assert rows["reference-ilc"]["mean_abs_error_rad"] < 0.2 * rows["pi"]["mean_abs_error_rad"]


def meta_check(bundle) -> list:
    return json.loads((bundle / "meta.json").read_text())["simulator_check"]


#: thresholds of the comparison below, with room for a run cut by its time cap on a slow machine; measured (this
#: test and benchmarks/closed_loop_goal.py): the closed-loop policy keeps >= 0.722 of its nominal gain, the
#: reference network 0.699; mean |Hall error| over cases and settings 0.0535 and 0.0656 rad
KEPT_SHARE_MIN = 0.6
CLOSEDLOOP_MEAN_RAD = 0.06
DEFAULT_MARGIN_MIN = 0.75
#: the published per-case table (docs/validation/_fragments/closed_loop_goal.md, 3 decimals): mean |Hall error|
#: (rad) per case and setting, hanging then ground, of the reference network and of the default
PUBLISHED_RAD = {"nominal": {"reference-ilc": (0.017, 0.072), "closedloop": (0.011, 0.051)},
                 "gait 0.7 s cycle": {"reference-ilc": (0.018, 0.095), "closedloop": (0.014, 0.069)},
                 "k x0.7": {"reference-ilc": (0.052, 0.220), "closedloop": (0.042, 0.171)},
                 "k x1.4": {"reference-ilc": (0.034, 0.099), "closedloop": (0.037, 0.087)},
                 "real-knee effects": {"reference-ilc": (0.022, 0.067), "closedloop": (0.026, 0.071)},
                 "curve": {"reference-ilc": (0.018, 0.075), "closedloop": (0.011, 0.052)}}
PUBLISHED_REL = 0.10  # within 10 %, plus half the table's last digit (0.0005 rad)


@pytest.mark.slow
def test_default_train_wins_the_comparison_meets_the_goal_and_is_robust(tmp_path):
    """`seadesign train --model reference,closedloop` on the thesis spring trains the reference network and the
    default, the closed-loop policy fine-tuning it (the same network the default trains). Over every case of
    `goal_cases` (the protocol, whose
    speeds no training used; a gait with a shorter cycle; k x0.7 and x1.4; real-knee effects; the softening curve),
    cell by cell (6 directions x 3 speeds x hanging and ground): both meet the goal on the protocol and the gait
    and are robust in the other cases (no flag, >= half the nominal gain per cell), and the closed-loop policy wins
    (lower mean |Hall error| over the cases), so the default is the winner of the closed-loop comparison."""
    from seadesign.cli import main

    spring = thesis_spring()
    path = write_spring(spring, tmp_path / "spring.json")
    res = CliRunner().invoke(main, ["train", "--spring", str(path), "--model", "reference,closedloop",
                                    "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    correctors = [load_corrector(tmp_path / "out" / folder)[0] for folder in ("reference-ilc", "closedloop")]
    names = [c.name for c in correctors]
    candidates = [NoCorrection(), HallPI(), FeedForward(spring["k_Nm_per_rad"]), *correctors]
    goals: dict[str, dict] = {name: {} for name in names}
    for case in goal_cases(spring):
        _, runs = case_table(candidates, spring, case, ("hanging", "ground"), thesis_protocol())
        for name in names:
            goals[name][case.name] = goal_table(runs, name)
    assert len(goals["closedloop"]["nominal"]) == 36
    verdicts = {name: verdict(goals[name]) for name in names}
    for name, v in verdicts.items():
        failed = {case: g[~g.meets_goal] for case, g in goals[name].items() if not g.meets_goal.all()}
        assert v["meets_goal"] and v["robust"] and v["kept_share_min"] >= KEPT_SHARE_MIN, (name, v, failed)
    assert winner(verdicts) == "closedloop", verdicts
    for case, by_name in PUBLISHED_RAD.items():  # the per-case table as published
        for name, published in by_name.items():
            g = goals[name][case]
            for setting, value in zip(("hanging", "ground"), published):
                got = float(g[g.setting == setting].mean_abs_error_rad.mean())
                assert abs(got - value) <= PUBLISHED_REL * value + 0.0005, (case, name, setting, got, value)
    assert verdicts["closedloop"]["mean_abs_error_rad"] < CLOSEDLOOP_MEAN_RAD
    # the default's bounded feedback keeps a wide loop-gain margin in both settings (measured 0.88 / 0.86 in
    # benchmarks/closed_loop_goal.py); 0.75 is half-way from there to the flag (0.5) and well above it
    from seadesign.corrector.stability import measure_loop_gain

    trials = thesis_protocol()[::3]  # 6 trials, as the benchmark
    for ground in (False, True):
        assert measure_loop_gain(correctors[1], spring, trials, ground=ground).modulus_margin > DEFAULT_MARGIN_MIN


@pytest.mark.parametrize("scale,offset_rad", [pytest.param(1.0, 0.0, marks=pytest.mark.slow), (2.0, 0.0),
                                              pytest.param(1.0, 0.05, marks=pytest.mark.slow)])
def test_simulator_check_reads_the_robots_stiffness_and_hall_offset_from_its_recording(tmp_path, scale, offset_rad):
    """A recording simulated with the spring's stiffness x `scale` and a Hall offset: the check recovers the scale,
    says whether it lies in the range the corrector is tested for (0.7-1.4), and finds a Hall offset exactly when
    there is one (the hanging shank's sag at rest, 0.048 rad, is no offset: the cleaning used to make it one)."""
    from seadesign.corrector.simcheck import check_simulator
    from seadesign.data import write_recording
    from seadesign.twin import KneeConfig, KneeSession, knee_effects

    spring = thesis_spring()
    chain = knee_effects(KneeConfig.from_spring(spring)).configure("stiffness_scale", enabled=True, scale=scale)
    if offset_rad:
        chain = chain.configure("hall_offset", enabled=True, offset_rad=offset_rad)
    session = KneeSession(spring, [Trial("front", 0.1, 15.0), Trial("right", 0.2, 15.0)], effects=chain)
    path = write_recording(session.run(), tmp_path / "walk.csv", metadata=session.metadata())
    checks = check_simulator(spring, [path])
    assert [c.knee for c in checks] == ["l", "r"]
    for c in checks:
        assert c.stiffness_scale == pytest.approx(scale, rel=0.06)  # measured 1.8-3 % low
        assert c.within_robust_range == (scale == 1.0)
        assert c.found == (("sensor_offset",) if offset_rad else ())
