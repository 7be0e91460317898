"""The knock-down on the path mesh's strain-limit torques holds against a second, finer mesh: on 8 x 4 mm the
default mesh (four graded layers through the thickness) reaches each tensile strain at a torque no lower than
the path mesh's times STRAIN_TORQUE_KNOCKDOWN. Marked default_mesh: a path on the default mesh takes minutes."""

from __future__ import annotations

import numpy as np
import pytest

from seadesign.design.study import load_study
from seadesign.fea.rotation_path import PathSettings, rotation_path
from seadesign.run.cache import Cache
from seadesign.sweep.requirements import STRAIN_TORQUE_KNOCKDOWN
from seadesign.sweep.stages import SolverSettings, check_geometry, tetrahedralize

LEVELS = (0.1, 0.2, 0.3, 0.65 / 1.5)  # tensile strains (-): the last is NinjaFlex's single-event limit


def _torque_at(path, level: float) -> float:
    strain = np.array([p.peak_tensile_strain for p in path.points])
    i = int(np.flatnonzero(strain >= level)[0])
    s = (level - strain[i - 1]) / (strain[i] - strain[i - 1])
    return path.points[i - 1].torque_Nm + s * (path.points[i].torque_Nm - path.points[i - 1].torque_Nm)


@pytest.mark.default_mesh
def test_the_path_mesh_strain_torques_knocked_down_lie_below_the_default_mesh():
    study, cache, solver = load_study(), Cache(), SolverSettings()
    candidate, part = check_geometry(study, study.candidate(beam_count=8, beam_thickness_mm=4.0), cache)
    part = part or study.check(candidate)[1]
    law, target = candidate.material.law, study.load_cases.impact_torque_Nm
    coarse = rotation_path(tetrahedralize(study, candidate, part, cache, layers=solver.path_layers), law, target,
                           PathSettings(), formulation=solver.path_formulation)
    fine = rotation_path(tetrahedralize(study, candidate, part, cache), law, target, PathSettings(),
                         formulation=solver.path_formulation)
    for level in LEVELS:
        assert STRAIN_TORQUE_KNOCKDOWN * _torque_at(coarse, level) <= _torque_at(fine, level), level
