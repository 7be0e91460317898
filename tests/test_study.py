"""Study files: the default study's derived inputs, and refusal of bad files by key."""

import math
import re
from pathlib import Path

import pytest

from seadesign.errors import ConfigError
from seadesign.design.study import DEFAULT_STUDY, load_study


def test_default_study():
    s = load_study()
    assert s.name == "wolfgang_knee"
    assert len(s.candidates()) == 24
    assert {(c.params.beam_count, c.params.beam_thickness_mm) for c in s.candidates()} == {
        (n, t) for n in range(3, 11) for t in (4.0, 6.0, 8.0)}
    # thesis eq. 5.1: tau = r F sin(theta) = 0.2038 m * 4 * 39.23 N * sin 60 deg = 27.70 Nm
    assert s.load_cases.impact_torque_Nm == pytest.approx(0.2038 * 4 * 39.23 * math.sin(math.pi / 3))
    assert round(s.load_cases.impact_torque_Nm, 2) == 27.70
    assert all(c.params.hub_radius_mm == 14.0 for c in s.candidates())
    hub = s.candidates()[0].params.hub_bolts
    assert (hub.count, hub.circle_diameter_mm) == (8, 22.0)


def test_bitbots_study_loads():
    s = load_study("bitbots_shoulder")
    ((_, p),) = [(c, c.params) for c in s.candidates()]
    assert (p.beam_count, p.beam_thickness_mm, p.ring_outer_radius_mm) == (6, 3.0, 25.0)


def _variant(tmp_path: Path, old: str, new: str) -> Path:
    text = DEFAULT_STUDY.read_text()
    assert re.search(old, text, flags=re.M), old
    path = tmp_path / "variant.toml"
    path.write_text(re.sub(old, new, text, count=1, flags=re.M))
    return path


@pytest.mark.parametrize(
    "old, new, message",
    [
        (r"^hub_radius_mm = 14.0", "hub_radius_mm = -3.0", "geometry.hub_radius_mm must be > 0"),
        (r"^beam_count = \[3, 4, 5, 6, 7, 8, 9, 10\]", "beam_count = [0, 3]", r"design_space.beam_count\[0\] must be > 0"),
        (r"^beam_count = \[3, 4, 5, 6, 7, 8, 9, 10\]", "beam_count = [3.5]", r"design_space.beam_count\[0\] must be one of the integers"),
        (r"^thickness_mm = 9.0", 'thickness_mm = "nine"', "geometry.thickness_mm must be a number"),
        (r"^thickness_mm = 9.0", "thickness_mm = 9.0\nthikness_mm = 9.0", "geometry.thikness_mm is not a known key"),
        (r"^stall_torque_Nm = 11.7.*$", "", "load_cases.stall_torque_Nm is missing"),
        (r"^material = .*$", 'material = "unobtainium"', "material cannot be loaded"),
        (r"^circle_diameter_mm = 56.0", "circle_diameter_mm = 40.0", "geometry.ring_bolts.circle_diameter_mm puts the holes"),
        (r"^bore_radius_mm = 4.0", "bore_radius_mm = 15.0", "geometry.bore_radius_mm"),
        (r"^beam_thickness_mm = \[4.0, 6.0, 8.0\]", "beam_thickness_mm = [4.0, 12.0]",
         "design_space.beam_thickness_mm value 12 mm needs geometry.arc_radius_mm > 6 mm"),
        (r"^safety_factor = 1.5", "safety_factor = 0.5", "ranking.safety_factor must be >= 1"),
        (r"^(knee_inertia_kg_m2 = .*)$", r"\1\ncontact_is_end_stop = true", "ranking.contact_is_end_stop is no "
         "longer used: the path goes on through frictionless self-contact .* remove the line"),
        (r"^(knee_inertia_kg_m2 = .*)$", r"\1\nself_contact = false", "ranking.self_contact is no longer used: the "
         "path always goes on through frictionless self-contact .* remove the line"),
    ],
)
def test_bad_study_is_refused_naming_the_key(tmp_path, old, new, message):
    path = _variant(tmp_path, old, new)
    with pytest.raises(ConfigError) as err:
        load_study(path)
    assert re.search(message, str(err.value)), str(err.value)
    assert str(path) in str(err.value)


def test_unknown_study_lists_known():
    with pytest.raises(ConfigError, match="nor among the packaged studies in .*wolfgang_knee"):
        load_study("nonexistent_study")


def test_every_lazy_command_resolves_and_every_command_is_listed():
    import importlib

    import click

    from seadesign.cli import COMMAND_MODULES, main

    ctx = click.Context(main)
    for name in COMMAND_MODULES:
        assert isinstance(main.get_command(ctx, name), click.Command), name
    for module in set(COMMAND_MODULES.values()):
        importlib.import_module(f"seadesign.cli.{module}")
    assert set(main.commands) == set(COMMAND_MODULES)  # no command defined but missing from the map


def test_old_duplicate_lower_leg_key_loads_with_a_deprecation_message(tmp_path):
    same = _variant(tmp_path, r"^foot_cell_count = 4", "foot_cell_count = 4\nlower_leg_m = 0.2038")
    with pytest.warns(FutureWarning, match="load_cases.lower_leg_m is deprecated"):
        s = load_study(same)
    assert s.load_cases.impact_torque_Nm == pytest.approx(load_study().load_cases.impact_torque_Nm, rel=1e-15)
    differ = _variant(tmp_path, r"^foot_cell_count = 4", "foot_cell_count = 4\nlower_leg_m = 0.25")
    with pytest.raises(ConfigError, match=r"load_cases.lower_leg_m \(0.25 m\) differs from robot.lower_leg_m"):
        load_study(differ)
