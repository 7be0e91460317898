"""spring.json schema: valid files pass, each kind of defect is refused with the field named."""

import json

import pytest

from seadesign.errors import SpringFileError
from seadesign.design.spring import load_spring, torque_curve, validate_spring, write_spring


def test_valid_spring_round_trips(spring_file, spring_dict):
    assert load_spring(spring_file) == json.loads(json.dumps(spring_dict))


@pytest.mark.parametrize(
    "mutate, field",
    [
        (lambda d: d.pop("k_Nm_per_rad"), "k_Nm_per_rad"),
        (lambda d: d.update(k_Nm_per_rad=-1.0), "k_Nm_per_rad"),
        (lambda d: d.update(k_Nm_per_rad="9.1"), "k_Nm_per_rad"),
        (lambda d: d["material"].update(poisson_ratio=0.5), "material/poisson_ratio"),
        (lambda d: d.update(surprise=1), r"\(top level\)"),
        (lambda d: d["actuator"].pop("gear_ratio"), "actuator/gear_ratio"),
    ],
)
def test_bad_spring_names_the_field(spring_dict, mutate, field):
    mutate(spring_dict)
    with pytest.raises(SpringFileError, match=f"field '{field}'"):
        validate_spring(spring_dict)


def test_writer_refuses_invalid(tmp_path, spring_dict):
    spring_dict["k_source"] = "guessed"
    with pytest.raises(SpringFileError, match="k_source"):
        write_spring(spring_dict, tmp_path / "s.json")
    assert not (tmp_path / "s.json").exists()


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(SpringFileError, match="does not exist"):
        load_spring(tmp_path / "nope.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(SpringFileError, match="not valid JSON"):
        load_spring(bad)


def test_schema_1_files_are_still_read(spring_dict):
    assert spring_dict["schema_version"] == 1 and validate_spring(spring_dict)
    assert torque_curve(spring_dict) is None


def _curve(**changes):
    return {"rotation_rad": [0.0, 0.1, 0.2, 0.3], "torque_Nm": [0.0, 1.8, 3.5, 4.9], "source": "fea_large_deflection",
            "stop_reason": "limit_point", "hard_stop": False, **changes}


def test_schema_2_carries_a_torque_curve(spring_dict):
    doc = dict(spring_dict, schema_version=2, torque_curve=_curve())
    curve = torque_curve(validate_spring(doc))
    assert curve.rotation_rad == (0.0, 0.1, 0.2, 0.3) and curve.torque_Nm[-1] == 4.9
    assert curve.stop_reason == "limit_point" and not curve.hard_stop


@pytest.mark.parametrize("changes, problem", [
    ({"torque_Nm": [0.0, 1.8, 1.7, 4.9]}, "increase strictly"),
    ({"rotation_rad": [0.0, 0.1, 0.2]}, "3 points"),
    ({"rotation_rad": [0.05, 0.1, 0.2, 0.3]}, "must start at \\(0, 0\\)"),
    ({"stop_reason": "gave up"}, "torque_curve/stop_reason"),
    ({"torque_Nm": [0.0, -1.0, 3.5, 4.9]}, "torque_curve/torque_Nm/1"),
])
def test_bad_torque_curve_names_the_field(spring_dict, changes, problem):
    with pytest.raises(SpringFileError, match=problem):
        validate_spring(dict(spring_dict, schema_version=2, torque_curve=_curve(**changes)))


def test_schema_3_refuses_a_curve_that_ends_at_contact_and_schema_2_is_still_read(spring_dict):
    """Schema 3's curves go on through self-contact: contact as their end is refused, naming the field and why;
    a schema-2 file whose curve stopped at first contact (as an end stop, too) is still read."""
    with pytest.raises(SpringFileError, match=r"field 'torque_curve/stop_reason': 'contact' is not allowed: schema 3 "
                                              r"curves go on through frictionless self-contact"):
        validate_spring(dict(spring_dict, schema_version=3, torque_curve=_curve(stop_reason="contact")))
    old = torque_curve(validate_spring(dict(spring_dict, schema_version=2,
                                            torque_curve=_curve(stop_reason="contact", hard_stop=True))))
    assert old.stop_reason == "contact" and old.hard_stop
    assert torque_curve(validate_spring(dict(spring_dict, schema_version=3, torque_curve=_curve(
        stop_reason="unconverged")))).stop_reason == "unconverged"


@pytest.mark.parametrize("reason", ["limit_point", "unconverged"])
def test_the_handed_curve_ends_at_the_paths_stop(reason):
    """The sweep's row holds the converged points, the last one past the stop (a limit point is located from
    both sides); spring.json gets the points before the stop and the stop itself, a valid monotone curve."""
    import pandas as pd

    from seadesign.design.spring import TorqueCurve
    from seadesign.sweep.handoff import handoff_curve

    row = pd.Series({"large_curve_rotation_rad": [0.0, 0.1, 0.2, 0.3, 0.31], "large_curve_torque_Nm":
                     [0.0, 1.8, 3.2, 4.0, 3.99], "large_stop_rotation_rad": 0.303, "large_stop_torque_Nm": 4.01,
                     "large_stop_reason": reason})
    curve = handoff_curve(row)
    assert curve["rotation_rad"] == [0.0, 0.1, 0.2, 0.3, 0.303] and curve["torque_Nm"] == [0.0, 1.8, 3.2, 4.0, 4.01]
    assert curve["stop_reason"] == reason and curve["hard_stop"] is False
    TorqueCurve.from_handoff(curve)  # strictly increasing from (0, 0)
