"""Issue goal: robot-format recordings with one effect (backlash, gear friction, sensor delay, sensor step,
thermal softening, or none), explained with the plain model and with the default declared chain.

Recordings (`helpers_generators.robot`, written apart from the simulator): one knee of a hanging robot stepping
in place, 100 Hz; 60 s (thermal softening: 120 s); torque -0.5..0.9 Nm reversing about four times a second;
Hall noise 0.002 rad, effort noise 0.05 Nm, 12-bit angles. Parameters drawn from seeded ranges, three draws
per case (the first by default, the others with the slow tests):

| effect | range | |
|---|---|---|
| backlash (dead_band) | width 0.02-0.05 rad | floor: 0.25 deg (0.0044 rad), the servo's own, is below the noise: unsupported |
| gear friction | Coulomb 0.2-0.5 Nm | |
| sensor delay | 20-60 ms | |
| sensor step | 0.03-0.15 rad at 20-80 % of the record | |
| thermal softening | 0.012-0.016 /J, cooling 300 s (23-34 % softer at the end) | floor: about 10 % softening by the end |

Plain model: exactly that effect is named (nothing for clean data), no ambiguity. Default declared chain
(backlash 0.25 deg and gear friction 0.3 Nm): the undeclared cases name exactly their effect and report both
declared effects unsupported; the backlash and gear-friction cases name nothing new, report "declared X, data
says Y" with Y within the tolerance, and the other declared effect unsupported.
"""

from __future__ import annotations

import pytest

from helpers_goal import GOAL, goal_recording
from seadesign.calibration import explain
from seadesign.calibration.sea import robot_declared, robot_loop_data

DRAWS = [0, pytest.param(1, marks=pytest.mark.slow), pytest.param(2, marks=pytest.mark.slow)]
@pytest.mark.parametrize("draw_index", DRAWS)
@pytest.mark.parametrize("case", list(GOAL))
def test_goal_plain_model_names_exactly_the_effect(spring_dict, case, draw_index):
    key, _, param, _, _, tol, _ = GOAL[case]
    df, value = goal_recording(case, draw_index)
    ex = explain(robot_loop_data(df, spring_dict), [])
    assert ex.found == ([key] if key else []) and not ex.ambiguities, ex.verdict()
    if key:
        assert ex.final.parameters()[key][param]["value"] == pytest.approx(value, rel=tol)


@pytest.mark.parametrize("draw_index", DRAWS)
@pytest.mark.parametrize("case", list(GOAL))
def test_goal_declared_chain_refits_and_reports_support(spring_dict, case, draw_index):
    key, declared_name, param, _, _, tol, _ = GOAL[case]
    df, value = goal_recording(case, draw_index)
    ex = explain(robot_loop_data(df, spring_dict), robot_declared(spring_dict))
    checks = {c.name: c for c in ex.declared}
    if declared_name:  # the effect is declared: no new effect; "declared X, data says Y" with Y right
        assert ex.found == [] and not ex.ambiguities, ex.verdict()
        check = checks[declared_name]
        assert check.supported, check.text()
        assert check.fitted[param]["value"] == pytest.approx(value, rel=tol)
        assert f"{param} declared {check.declared[param]:.4g}, data says" in check.text()
        assert ex.unsupported == [n for n in ("backlash", "gear_friction") if n != declared_name]
    else:
        assert ex.found == ([key] if key else []) and not ex.ambiguities, ex.verdict()
        assert ex.unsupported == ["backlash", "gear_friction"], ex.verdict()
        if key:
            assert ex.final.parameters()[key][param]["value"] == pytest.approx(value, rel=tol)
    assert not checks["stiffness_scale"].supported  # the declared k holds: the scale is consistent with 1
