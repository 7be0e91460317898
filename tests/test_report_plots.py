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
                         for x in ("rotation_rad", "torque_Nm")},
                      "large_contact_rotation_rad": [0.05 if i == chosen else np.nan for i in range(n)],
                      "large_contact_torque_Nm": 10.0})
    figures = []
    monkeypatch.setattr(plots.plt, "close", figures.append)
    plots.fig_curves(t, chosen, 10.0, 20.0, tmp_path / "curves.png")
    legend = figures[0].axes[0].get_legend()
    names = [text.get_text().split(" (")[0] for text in legend.get_texts()]
    lightest = [f"design {i}" for i in np.argsort(mass) if i != chosen][: plots.LEGEND_CURVES - 1]
    assert names == [f"design {chosen}", *lightest]
    assert legend.get_title().get_text().startswith(f"{n - plots.LEGEND_CURVES} more")
    assert (tmp_path / "curves.png").stat().st_size > 0
    crosses = [line for line in figures[0].axes[0].get_lines() if line.get_marker() == "x"]
    assert [(tuple(c.get_xdata()), tuple(c.get_ydata())) for c in crosses] == [((0.05,), (10.0,))]  # first contact


def test_the_choice_is_drawn_in_colour_off_the_front_and_an_unconverged_end_has_its_own_marker(tmp_path, monkeypatch):
    """A nearest design that is not on the Pareto front (nothing feasible) is still the red, named curve; its end
    (unconverged in a crease) is a diamond, the grey curves carry no markers."""
    t = pd.DataFrame({"candidate": ["front", "choice", "other"], "status": "ok", "pareto": [True, False, False],
                      "mass_g": [20.0, 30.0, 25.0], "large_curve_rotation_rad": [[0.0, 0.3]] * 3,
                      "large_curve_torque_Nm": [[0.0, 5.0], [0.0, 10.0], [0.0, 4.0]],
                      "large_stop_reason": ["bifurcation", "unconverged", "unconverged"],
                      "large_stop_rotation_rad": 0.3, "large_stop_torque_Nm": [5.0, 10.0, 4.0],
                      **{f"large_{kind}_limit_{x}": np.nan for kind in ("cyclic", "single")
                         for x in ("rotation_rad", "torque_Nm")},
                      "large_contact_rotation_rad": [np.nan, 0.2, 0.2], "large_contact_torque_Nm": [np.nan, 7.0, 3.0]})
    figures = []
    monkeypatch.setattr(plots.plt, "close", figures.append)
    plots.fig_curves(t, 1, 11.7, 27.7, tmp_path / "curves.png")
    ax = figures[0].axes[0]
    assert [text.get_text() for text in ax.get_legend().get_texts()] == ["choice (unconverged)", "front (bifurcation)"]
    ends = {(line.get_marker(), line.get_color(), float(line.get_ydata()[0])) for line in ax.get_lines()
            if line.get_marker() in ("D", "v")}
    assert ends == {("D", "r", 10.0), ("v", plots._NOT_RED[1], 5.0)}


def test_parallel_coordinates_draw_a_categorical_axis_as_its_categories(tmp_path, monkeypatch):
    """The material axis (strings) is drawn as its categories: each design's line passes through its own
    material's tick, and the ticks are named (it was drawn as "nan-nan" with no line through it)."""
    from seadesign.report import explore_plots

    materials = ["ninjaflex", "cheetah", "cheetah", "ninjaflex", "cheetah"]
    evaluated = pd.DataFrame({"thickness_mm": [6.0, 8.0, 10.0, 12.0, 14.0], "material": pd.array(materials, dtype="str"),
                              "mass_g": [20.0, 25.0, 30.0, 35.0, 40.0], "feasible": [True, False, False, True, False],
                              "conditional": [False, True, False, False, True]})
    invalid = pd.DataFrame({"thickness_mm": [7.0], "material": pd.array(["cheetah"], dtype="str")})
    figures = []
    monkeypatch.setattr(explore_plots.plt, "close", figures.append)
    explore_plots.fig_parallel(evaluated, invalid, ["thickness_mm", "material"], ["mass_g"], 1, tmp_path / "p.png")
    ax = figures[0].axes[0]
    design_lines = [line for line in ax.get_lines() if len(line.get_xdata()) == 3]
    assert len(design_lines) == 7  # 5 evaluated, 1 invalid, the choice again
    # categories sorted: cheetah 0, ninjaflex 1 on the material column (x = 1)
    expected = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]  # the five evaluated, the invalid one, the choice (cheetah)
    assert sorted(line.get_ydata()[1] for line in design_lines) == sorted(expected)
    assert {t.get_text() for t in ax.texts} == {"cheetah", "ninjaflex"}
    assert "nan" not in " ".join(t.get_text() for t in ax.get_xticklabels())
