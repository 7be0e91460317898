"""Write a solve to disk: results JSON and the deformed mesh as VTU (quadratic tetrahedra)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from seadesign.fea.loadcases import Analysis
from seadesign.fea.stress import invariants
from seadesign.fea.torsion import MM

VTK_QUADRATIC_TETRA = 24  # node order = ours (C3D10)
VTK_TETRA = 10


def write_vtu(analysis: Analysis, path: Path) -> Path:
    """VTU with, per load case, displacement (mm) and von Mises, principal and shear stresses (MPa)."""
    import pyvista as pv

    em = analysis.unit.emesh
    cell_type = VTK_QUADRATIC_TETRA if em.order == 2 else VTK_TETRA
    nen = em.elements.shape[1]
    cells = np.hstack([np.full((len(em.elements), 1), nen), em.elements]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(em.elements), cell_type, dtype=np.uint8), em.nodes_m / MM)
    for case in analysis.hub_torque_Nm:
        grid.point_data[f"{case}_displacement_mm"] = analysis.displacement_m(case) / MM
        stress = analysis.stress_Pa(case)
        grid.point_data[f"{case}_stress_MPa"] = stress * 1e-6  # xx yy zz xy yz zx
        for name, values in invariants(stress).items():
            grid.point_data[f"{case}_{name}_MPa"] = values * 1e-6
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    grid.save(path)
    return path


def write_results_json(results: dict, path: Path, meta: dict | None = None) -> Path:
    """Results (plain numbers, units in the keys) plus metadata as indented JSON."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"results": results, **(meta or {})}, indent=2, sort_keys=True, default=str))
    return path
