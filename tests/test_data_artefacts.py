"""Artefact detection and cleaning on crafted recordings with known artefacts, and on the real files."""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.data import clean, detect_artefacts, read_recording, write_cleaned, write_recording
from seadesign.errors import DataError
from seadesign.twin import Gait, KneeConfig, KneeSession, Trial, configure_chain, knee_effects
from tests.conftest import shared_path


@pytest.fixture(scope="module")
def quiet_recording():
    """20 s hanging, 100 Hz, 2 s rest at the start; a clean baseline (no noise)."""
    spring = {
        "schema_version": 1, "study": "t", "k_source": "measured", "k_Nm_per_rad": 9.106, "k_rel_error": None,
        "design": {"beam_count": 9, "beam_thickness_mm": 8.0},
        "material": {"name": "n", "youngs_modulus_Pa": 12e6, "poisson_ratio": 0.48, "density_kg_per_m3": 1190.0,
                     "yield_strength_Pa": 4e6},
        "actuator": {"stall_torque_Nm": 11.7, "no_load_speed_rad_per_s": 4.817, "gear_ratio": 272.5,
                     "backlash_rad": 0.00436},
        "robot": {"mass_kg": 8.0, "lower_leg_m": 0.2038, "upper_leg_m": 0.2},
        "inputs_hash": "0123456789abcdef", "versions": {},
    }
    cfg = KneeConfig.from_spring(spring)
    chain = configure_chain(knee_effects(cfg), ["hall_noise=off", "effort_noise=off"])
    session = KneeSession(spring, [Trial("front", 0.1, 20.0)], effects=chain, config=cfg, gait=Gait(stand_s=2.0))
    return session.run()


def _write_read(tmp_path, df):
    return read_recording(write_recording(df, tmp_path / "crafted.csv"))


def test_clean_simulation_has_no_artefacts(tmp_path, quiet_recording):
    rep = detect_artefacts(_write_read(tmp_path, quiet_recording))
    for side in "lr":
        k = rep.knees[side]
        assert not k["steps"] and not k["wraps"] and not k["stuck"] and k["glitches"] == 0
    assert rep.sampling["gaps"] == 0 and rep.sampling["rate_median_hz"] == pytest.approx(100.0)


def test_known_offset_wrap_step_glitch_stuck_and_gap(tmp_path, quiet_recording):
    df = quiet_recording.copy()
    true_rest = detect_artefacts(df).knees["l"]["offset"]["first_rest_rad"]
    hall = df["l_hall_pos"].to_numpy().copy()
    hall -= 0.2                      # offset: deflection + 0.2
    hall[600:] -= 2 * np.pi          # a wrap at row 600
    hall[1200:] += 0.5               # a level step at row 1200
    hall[900] += 0.8                 # a one-sample glitch
    hall[1500:1600] = hall[1500]     # stuck for 1 s while the knee walks
    df["l_hall_pos"] = hall
    df = df.drop(index=range(1700, 1750)).reset_index(drop=True)  # a 0.5 s gap (50 samples)
    rep = detect_artefacts(_write_read(tmp_path, df))
    k = rep.knees["l"]
    assert k["offset"]["first_rest_rad"] == pytest.approx(true_rest + 0.2, abs=1e-9)
    assert [w["row"] for w in k["wraps"]] == [600]
    assert k["wraps"][0]["size_rad"] == pytest.approx(-2 * np.pi, abs=0.3)
    # the level step, and the jump back out of the stuck segment
    assert [s["row"] for s in k["steps"]] == [1200, 1600] and k["steps"][0]["size_rad"] == pytest.approx(0.5, abs=0.1)
    assert k["glitches"] == 1
    assert len(k["stuck"]) == 1 and k["stuck"][0]["rows"] == [1500, 1600]
    assert rep.sampling["gaps"] == 1 and rep.sampling["dropped_samples_est"] == 50
    assert not rep.knees["r"]["steps"] and not rep.knees["r"]["wraps"]


def test_cleaning_counts_every_removed_row_and_undoes_wrap_and_offset(tmp_path, quiet_recording):
    df = quiet_recording.copy()
    hall = df["l_hall_pos"].to_numpy().copy()
    hall -= 0.2
    hall[600:] -= 2 * np.pi
    hall[900] += 0.8
    df["l_hall_pos"] = hall
    res = clean(_write_read(tmp_path, df), keep_lifted=True, normalise=False, euler=True)
    assert len(res.table) + sum(res.removed.values()) == len(df)
    assert {k: v for k, v in res.removed.items() if v} == {"l_hall_glitch": 1}
    ref = clean(quiet_recording, keep_lifted=True, normalise=False)
    keep = np.ones(len(df), dtype=bool)
    keep[900] = False
    np.testing.assert_allclose(res.table["l_hall_pos"], ref.table["l_hall_pos"].to_numpy()[keep], atol=1e-9)
    assert {"imu_roll_rad", "imu_pitch_rad", "imu_yaw_rad"} <= set(res.table.columns)
    steps = [s["step"] for s in res.log]
    assert steps.index("unwrap") < steps.index("remove_offset") < steps.index("euler")
    out = write_cleaned(res, tmp_path / "clean.csv")
    assert out.with_name("clean.meta.json").exists()


def test_cleaning_thesis_steps(quiet_recording):
    with pytest.raises(DataError, match="hanging recording"):
        clean(quiet_recording)
    res = clean(quiet_recording, keep_lifted=True, remove_offset=False, positive=True)
    np.testing.assert_allclose(res.table["l_knee_pos"], quiet_recording["l_knee_pos"] / np.pi)
    np.testing.assert_allclose(res.table["r_knee_pos"], -quiet_recording["r_knee_pos"] / np.pi)
    lifted = quiet_recording.copy()
    lifted.loc[:99, [f"l_pressure_{i}" for i in range(4)]] = 0.0
    lifted.loc[100:, "l_pressure_0"] = 50.0
    res = clean(lifted, pressure_threshold=10.0)
    assert res.removed["lifted"] == 100


@pytest.mark.parametrize(
    "name, expect",
    [
        ("d1free.csv", {"l_steps": 6, "l_stuck_min": 8, "gaps_min": 100}),
        ("free_dtest_part1.csv", {"l_steps": 0, "l_stuck_min": 0, "gaps_min": 50}),
        ("ground_dtest_part1.csv", {"l_steps": 0, "l_stuck_min": 1, "gaps_min": 100}),
    ],
)
def test_real_recordings(name, expect):
    df = read_recording(shared_path("data", "deepsea", name))
    rep = detect_artefacts(df)
    k = rep.knees["l"]
    assert len(k["steps"]) == expect["l_steps"]
    assert len(k["stuck"]) >= expect["l_stuck_min"]
    assert rep.sampling["gaps"] >= expect["gaps_min"]
    assert 140 < rep.sampling["rate_median_hz"] < 170
    if name.startswith("ground"):
        assert k["offset"]["first_rest_rad"] < -0.5 and k["offset"]["first_rest_pressure"] > 10  # sag under load
    hanging = not name.startswith("ground")
    res = clean(df, keep_lifted=hanging, normalise=False)
    assert len(res.table) + sum(res.removed.values()) == len(df)
    lifted = df[[c for c in df.columns if "_pressure_" in c]].to_numpy().sum(axis=1) < 10.0
    assert res.removed.get("l_hall_stuck", 0) == int((rep.masks["l"]["stuck"] & (~lifted | hanging)).sum())
    # what cleaning promises, checked on its output by the detector: nothing stuck, no glitch, step or wrap is
    # left; a hanging recording's Hall offset at rest is gone, a ground recording's (no unloaded rest) is kept
    after = detect_artefacts(res.table)
    for side in "lr":
        k2 = after.knees[side]
        assert not k2["stuck"] and k2["glitches"] == 0 and not k2["steps"] and not k2["wraps"], side
        if hanging:
            assert abs(k2["offset"]["rest_median_rad"]) < 1e-3
        else:
            assert k2["offset"]["rest_median_rad"] < -0.5
            assert any(e["step"] == "remove_offset" and "skipped" in e["detail"] and e["detail"].startswith(side)
                       for e in res.log)
