"""Off-screen pyvista render of a candidate's large-deflection state, true scale, coloured by strain."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)
COLOUR_PERCENTILE = 99.0  # the colour scale ends at this percentile of the vertex strain (a fillet's peak would
# otherwise squeeze the rest of the part into one colour); above it: red
VTK_WINDOW_ENV = "VTK_DEFAULT_OPENGL_WINDOW"  # the render window class VTK creates (VTK >= 9.4)


def use_headless_window() -> None:
    """Without a display, VTK tries an X window first, prints "bad X server connection" and only then falls back
    to EGL: on Linux without DISPLAY, ask for the EGL window directly (unless VTK_DEFAULT_OPENGL_WINDOW is set)."""
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        os.environ.setdefault(VTK_WINDOW_ENV, "vtkEGLRenderWindow")


def render_path(path_response, strain_limit: float, title: str, path: Path) -> Path | None:
    """PNG of the path's snapshot state (`sweep.path_stage.PathResponse`, at the stall torque) at true scale,
    coloured by the largest tensile principal engineering strain (%) up to its 99th percentile (red above; the
    stall's strain limit and the peak in the caption); None (with a logged message) when off-screen rendering
    is unavailable."""
    try:
        import pyvista as pv

        use_headless_window()
        r = path_response
        cells = np.hstack([np.full((len(r.tets), 1), 4), r.tets]).ravel()
        grid = pv.UnstructuredGrid(cells, np.full(len(r.tets), pv.CellType.TETRA, dtype=np.uint8),
                                   r.points_mm + r.vertex_displacement_m * 1e3)
        strain = r.vertex_strain * 100.0
        grid.point_data["tensile strain (%)"] = strain
        top = float(np.percentile(strain, COLOUR_PERCENTILE))
        plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
        plotter.add_mesh(grid.extract_surface(algorithm=None), scalars="tensile strain (%)", cmap="viridis",
                         clim=(0.0, top), above_color="red", show_edges=False)
        allowed = "" if not np.isfinite(strain_limit) else f"; cyclic limit {100 * strain_limit:.3g} %"
        plotter.add_text(f"{title}\n{r.snapshot_rotation_rad:.3g} rad, {r.snapshot_torque_Nm:.3g} Nm, true scale; red: "
                         f"strain above {top:.3g} % (peak {float(strain.max()):.3g} %{allowed})", font_size=10)
        plotter.view_xy()
        plotter.camera.elevation = -30
        path.parent.mkdir(parents=True, exist_ok=True)
        plotter.screenshot(str(path))
        plotter.close()
        return path
    except Exception as exc:  # noqa: BLE001 - no display / no OpenGL: the report goes on without renders
        log.warning("skipping the render: off-screen rendering is unavailable (%s)", exc)
        return None
