"""The torque-curve figure stays readable with an explorer's front of dozens of designs: the legend names the
choice and then the lightest, at most LEGEND_CURVES of them, and says how many more are drawn."""

from __future__ import annotations

import numpy as np
import pandas as pd

from seadesign.report import plots


def test_torque_curve_legend_names_the_choice_then_the_lightest(tmp_path, monkeypatch):
    n, chosen = plots.LEGEND_CURVES + 5, 7
    rng = np.random.default_rng(0)
    mass = rng.permutation(np.arange(40.0, 40.0 + n))
    t = pd.DataFrame({"candidate": [f"design {i}" for i in range(n)], "status": "ok", "pareto": True,
                      "mass_g": mass, "large_curve_rotation_rad": [[0.0, 0.1 + 0.01 * i] for i in range(n)],
                      "large_curve_torque_Nm": [[0.0, 20.0] for _ in range(n)], "large_stop_reason": "target_reached",
                      "large_stop_rotation_rad": [0.1 + 0.01 * i for i in range(n)], "large_stop_torque_Nm": 20.0,
                      **{f"large_{kind}_limit_{x}": np.nan for kind in ("cyclic", "single")
                         for x in ("rotation_rad", "torque_Nm")}})
    figures = []
    monkeypatch.setattr(plots.plt, "close", figures.append)
    plots.fig_curves(t, chosen, 10.0, 20.0, tmp_path / "curves.png")
    legend = figures[0].axes[0].get_legend()
    names = [text.get_text().split(" (")[0] for text in legend.get_texts()]
    lightest = [f"design {i}" for i in np.argsort(mass) if i != chosen][: plots.LEGEND_CURVES - 1]
    assert names == [f"design {chosen}", *lightest]
    assert legend.get_title().get_text().startswith(f"{n - plots.LEGEND_CURVES} more")
    assert (tmp_path / "curves.png").stat().st_size > 0
