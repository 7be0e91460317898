"""Typed FEA results: every quantity declares how it scales with the applied torque (and a linear
solve's, with the modulus), and the declared rules reproduce a direct solve at another torque or
modulus."""

from __future__ import annotations

import dataclasses
import inspect

import pytest
from helpers_parts import holed_annulus

import seadesign.fea.results as results_module
from seadesign.fea.loadcases import analyse
from seadesign.fea.results import LinearResults, scaled
from seadesign.mesh import mesh_part


def _result_types():
    return [c for _, c in inspect.getmembers(results_module, inspect.isclass)
            if dataclasses.is_dataclass(c) and c.__module__ == results_module.__name__]


@pytest.mark.parametrize("cls", _result_types(), ids=lambda c: c.__name__)
def test_every_field_has_a_torque_rule(cls):
    for f in dataclasses.fields(cls):
        nested = dataclasses.is_dataclass(f.type) or f.type in {c.__name__ for c in _result_types()}
        assert nested or "scaling" in f.metadata, f"{cls.__name__}.{f.name} has no torque-scaling rule"


def test_a_field_without_a_rule_is_refused():
    @dataclasses.dataclass(frozen=True)
    class Forgotten:
        torque_Nm: float = results_module.linear()
        new_output_mm: float = 0.0

    with pytest.raises(TypeError, match="new_output_mm has no torque-scaling rule"):
        scaled(Forgotten(1.0, 2.0), 3.0)


@pytest.fixture(scope="module")
def annulus(tmp_path_factory):
    """A holed annulus's mesh and its solve at 12 MPa under 11.7 / 27.7 Nm."""
    solid, ifc = holed_annulus()
    mesh = mesh_part(solid, ifc, elements_across_beam=1, beam_width_mm=3.0, cache_dir=tmp_path_factory.mktemp("mesh"))
    return mesh, analyse(mesh, 12e6, 0.48, 4e6, 11.7, 27.7, bearing_radius_mm=9.0).results


def test_scaled_unit_solve_equals_a_direct_solve(annulus):
    """The rules applied to a 1 Nm solve give the numbers of a solve at the load torques (every
    column but the timings): a quantity with a wrong rule (say a safety factor declared linear) fails."""
    mesh, solved = annulus
    unit = analyse(mesh, 12e6, 0.48, 4e6, 1.0, 1.0, bearing_radius_mm=9.0).results
    direct = solved.columns()
    via_rules = unit.at(11.7, 27.7).columns()
    assert set(via_rules) == set(direct)
    for key, value in direct.items():
        if not key.startswith("time_"):
            assert via_rules[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key


def _linear_types(cls=LinearResults):
    inner = [f.type for f in dataclasses.fields(cls) if f.type in {c.__name__ for c in _result_types()}]
    return [cls] + [t for name in inner for t in _linear_types(getattr(results_module, name))]


@pytest.mark.parametrize("cls", _linear_types(), ids=lambda c: c.__name__)
def test_every_field_of_a_linear_solve_has_a_modulus_rule(cls):
    for f in dataclasses.fields(cls):
        nested = f.type in {c.__name__ for c in _result_types()}
        assert nested or f.metadata.get("modulus") is not None, f"{cls.__name__}.{f.name} has no modulus rule"


def test_a_field_without_a_modulus_rule_is_refused():
    @dataclasses.dataclass(frozen=True)
    class Curve:
        torque_Nm: float = results_module.unscaled()

    with pytest.raises(TypeError, match="torque_Nm has no modulus-scaling rule"):
        results_module.with_modulus(Curve(1.0), 2.0)


def test_a_solve_at_another_modulus_equals_the_rules(annulus):
    """The modulus rules applied to a solve give the numbers of a direct solve at 2.7 times the modulus (the
    same Poisson ratio): k as E, rotations and displacements as 1 / E, stresses and reactions unchanged; a
    quantity with a wrong rule (a stress declared to scale) fails."""
    mesh, base = annulus
    direct = analyse(mesh, 2.7 * 12e6, 0.48, 4e6, 11.7, 27.7, bearing_radius_mm=9.0).results.columns()
    via_rules = base.with_modulus(2.7).columns()
    assert via_rules["k_Nm_per_rad"] == pytest.approx(2.7 * base.k_Nm_per_rad, rel=1e-14)
    for key, value in direct.items():
        if not key.startswith("time_") and key != "equilibrium_rel_error":
            assert via_rules[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key  # measured 1.8e-13
