"""Off-screen pyvista renders of a solved candidate's deformed shape coloured by von Mises stress."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)
MAX_DRAWN_DISPLACEMENT = 0.1  # largest drawn displacement as a fraction of the part's diameter
COLOUR_PERCENTILE = 99.0  # the colour scale ends at this percentile of nodal von Mises (peaks at the
# rigid couplings would otherwise squeeze the rest of the part into one colour); above it: red


def render_case(unit, case: str, torque_Nm: float, title: str, path: Path) -> Path | None:
    """PNG of the deformed mesh (displacement scaled to at most 10 % of the diameter, scale in the
    title) coloured by von Mises stress in MPa up to its 99th percentile (red above); None (with a logged message) when off-screen
    rendering is unavailable."""
    try:
        import pyvista as pv

        pv.OFF_SCREEN = True
        cells = np.hstack([np.full((len(unit.tets), 1), 4), unit.tets]).ravel()
        grid = pv.UnstructuredGrid(cells, np.full(len(unit.tets), pv.CellType.TETRA, dtype=np.uint8), unit.points_mm)
        u_mm = unit.vertex_displacement_m[case] * torque_Nm * 1e3
        diameter = float(np.ptp(unit.points_mm[:, 0]))
        peak = float(np.linalg.norm(u_mm, axis=1).max())
        scale = min(1.0, MAX_DRAWN_DISPLACEMENT * diameter / peak) if peak > 0 else 1.0
        grid.points = unit.points_mm + scale * u_mm
        grid.point_data["von Mises (MPa)"] = unit.vertex_von_mises_Pa * abs(torque_Nm) * 1e-6
        vm = grid.point_data["von Mises (MPa)"]
        top = float(np.percentile(vm, COLOUR_PERCENTILE))
        plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
        plotter.add_mesh(grid.extract_surface(algorithm=None), scalars="von Mises (MPa)", cmap="viridis",
                         clim=(0.0, top), above_color="red", show_edges=False)
        plotter.add_text(f"{title}\ndisplacement drawn x{scale:.3g} (true peak {peak:.3g} mm); red: von Mises above "
                         f"{top:.3g} MPa (peak {float(vm.max()):.3g} MPa)", font_size=10)
        plotter.view_xy()
        plotter.camera.elevation = -30
        path.parent.mkdir(parents=True, exist_ok=True)
        plotter.screenshot(str(path))
        plotter.close()
        return path
    except Exception as exc:  # noqa: BLE001 - no display / no OpenGL: the report goes on without renders
        log.warning("skipping the %s render: off-screen rendering is unavailable (%s)", case, exc)
        return None
