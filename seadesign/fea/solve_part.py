"""One part, end to end: mesh -> both load cases -> optional exports. Lengths mm, physics SI."""

from __future__ import annotations

import time
from pathlib import Path

from seadesign.fea.ccx import write_load_case_decks
from seadesign.fea.export import write_results_json, write_vtu
from seadesign.fea.loadcases import Analysis, analyse
from seadesign.mesh import TetMesh, mesh_part
from seadesign.design.interfaces import Interfaces


def solve_part(
    solid_or_surface,
    interfaces: Interfaces,
    youngs_modulus_Pa: float,
    poisson_ratio: float,
    yield_strength_Pa: float,
    stall_torque_Nm: float,
    impact_torque_Nm: float,
    bearing_radius_mm: float,
    elements_across_beam: float,
    beam_width_mm: float,
    backend: str = "gmsh",
    elements_per_circle: float = 0.0,
    layers: int = 0,
    cache_dir: str | Path | None = None,
    out_dir: str | Path | None = None,
    export_ccx_dir: str | Path | None = None,
    name: str = "part",
) -> tuple[dict, Analysis, TetMesh]:
    """Mesh and solve a part (CadQuery solid or closed surface); with out_dir write
    <name>.json and <name>.vtu, with export_ccx_dir the CalculiX decks stall.inp / impact.inp."""
    t0 = time.perf_counter()
    mesh = mesh_part(solid_or_surface, interfaces, elements_across_beam, beam_width_mm, cache_dir=cache_dir,
                     backend=backend, elements_per_circle=elements_per_circle, layers=layers)
    t1 = time.perf_counter()
    a = analyse(mesh, youngs_modulus_Pa, poisson_ratio, yield_strength_Pa, stall_torque_Nm, impact_torque_Nm,
                bearing_radius_mm)
    results = {**a.results.columns(), "time_mesh_s": t1 - t0, "time_total_s": time.perf_counter() - t0}
    if out_dir is not None:
        out_dir = Path(out_dir)
        meta = {
            "mesh": {k: v for k, v in mesh.info.items()},
            "inputs": {
                "youngs_modulus_Pa": youngs_modulus_Pa, "poisson_ratio": poisson_ratio,
                "yield_strength_Pa": yield_strength_Pa, "bearing_radius_mm": bearing_radius_mm,
            },
            "notes": {
                "impact_peak_nodal_reaction_N": "largest single nodal force on the hub coupling; mesh dependent "
                "(P2 splits loads unevenly between corner and midside nodes), reported for comparison with NASTRAN",
            },
        }
        write_results_json(results, out_dir / f"{name}.json", meta)
        write_vtu(a, out_dir / f"{name}.vtu")
    if export_ccx_dir is not None:
        write_load_case_decks(export_ccx_dir, a.unit, youngs_modulus_Pa, poisson_ratio, stall_torque_Nm, impact_torque_Nm)
    return results, a, mesh
