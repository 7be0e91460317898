"""The strain render on a machine without a display: a real image, and no VTK noise on the console."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]

# A twisted block of tetrahedra, strained along x, rendered as the sweep renders its chosen part.
RENDER = textwrap.dedent("""
    import sys
    from pathlib import Path
    import numpy as np
    import pyvista as pv
    from seadesign.report.renders import render_path
    from seadesign.sweep.path_stage import PathResponse

    block = pv.ImageData(dimensions=(9, 5, 3), spacing=(4.0, 4.0, 4.0)).triangulate()
    points = np.asarray(block.points, float)
    tets = np.asarray(block.cells_dict[pv.CellType.TETRA])
    twist = np.column_stack([-points[:, 1], points[:, 0], np.zeros(len(points))]) * 1e-5 * points[:, :1]
    response = PathResponse(None, points, tets, twist, points[:, 0] / 320.0, 0.3, 2.5, None)
    written = render_path(response, 0.08, "test block", Path(sys.argv[1]))
    print("written:", written)
""")


@pytest.mark.parametrize("display", [None, ""], ids=["DISPLAY unset", "DISPLAY empty"])
def test_a_render_without_a_display_is_written_quietly(tmp_path, display):
    import matplotlib.image

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    if display is not None:
        env["DISPLAY"] = display
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")])
    png = tmp_path / "render.png"
    run = subprocess.run([sys.executable, "-c", RENDER, str(png)], env=env, cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    output = run.stdout + run.stderr
    assert run.returncode == 0, output
    assert f"written: {png}" in output
    for noise in ("bad X server", "vtkXOpenGLRenderWindow", "WARN"):
        assert noise not in output, output
    image = matplotlib.image.imread(png)[..., :3]
    assert image.shape == (700, 900, 3)
    colours = np.unique((image * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 100  # the colour scale across the part and the legend, the text, the background
    drawn = np.abs(image - image[0, -1]).sum(axis=2) > 0.1  # differs from the background (top right corner)
    assert drawn.mean() > 0.15  # the block covers about a quarter of the picture
