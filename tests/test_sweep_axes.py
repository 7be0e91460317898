"""Any geometry key can be a design axis: a study whose only axis is the axial thickness sweeps,
ranks, reports and hands off with no code change; dotted keys name nested values."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from seadesign.cli import main
from seadesign.design.spring import load_spring
from seadesign.design.study import DEFAULT_STUDY, load_study
from seadesign.errors import ConfigError
from sweep_helpers import write_tiny_study


def _study_text(**lines: str) -> str:
    """The default study with some lines replaced: key -> the new line(s) (first occurrence)."""
    text = DEFAULT_STUDY.read_text()
    for key, new in lines.items():
        text, n = re.subn(rf"(?m)^{key}\s*=.*$", new, text, count=1)
        assert n == 1, key
    return text


def thickness_study(folder: Path) -> Path:
    text = _study_text(thickness_mm="beam_count = 5\nbeam_thickness_mm = 6.0", name='name = "axial"',
                       beam_count="thickness_mm = [8.0, 12.0]", beam_thickness_mm="", elements_across_beam=
                       "elements_across_beam = 0.6", elements_per_circle="elements_per_circle = 0", layers="layers = 2")
    path = folder / "axial.toml"
    path.write_text(text)
    return path


@pytest.mark.slow  # about 45 s: a sweep of several thicknesses through the path
def test_axial_thickness_axis_sweeps_ranks_reports_and_hands_off(tmp_path):
    path = thickness_study(tmp_path)
    study = load_study(path)
    assert [a.key for a in study.axes] == ["thickness_mm"]
    assert [c.name for c in study.candidates()] == ["thickness 8 mm", "thickness 12 mm"]
    out = tmp_path / "exports"
    result = CliRunner().invoke(main, ["sweep", str(path), "--jobs", "1", "--quiet", "--out", str(out),
                                       "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 0, result.output
    t = pd.read_csv(out / "axial" / "results.csv")
    assert "thickness_mm" in t and "beam_count" not in t and "beam_thickness_mm" not in t
    assert (t["status"] == "ok").all()
    k = t.set_index("thickness_mm")["k_Nm_per_rad"]
    # beams bent in their plane: k per unit thickness grows from the plane-stress value (thin part)
    # toward the plane-strain one, 1 / (1 - nu^2) times higher (deep part), so thicker is at least
    # proportionally and at most 1 / (1 - nu^2) times more than proportionally stiffer
    nu = study.material.poisson_ratio
    assert 1.5 < k[12.0] / k[8.0] < 1.5 / (1 - nu**2)
    spring = load_spring(out / "axial" / "spring.json")
    chosen = t.loc[t["rank"] == 1].iloc[0]
    assert spring["design"]["thickness_mm"] == chosen["thickness_mm"]
    assert (spring["design"]["beam_count"], spring["design"]["beam_thickness_mm"]) == (5, 6.0)
    for name in ("report.html", "k_vs_thickness_mm.png", "reaction_displacement.png", "pareto.png",
                 f"{chosen['candidate'].replace(' ', '')}.stl"):
        assert (out / "axial" / name).is_file(), name
    assert "thickness" in (out / "axial" / "report.md").read_text()


def test_dotted_key_axis_and_conflicts(tmp_path):
    path = write_tiny_study(tmp_path, beam_count="[3]")
    text = path.read_text().replace("[design_space]\n", "[design_space]\n\"hub_bolts.count\" = [4, 8]\n")
    text = re.sub(r"(?m)^(\[geometry.hub_bolts\][^\n]*\n)count = 8", r"\1", text)
    path.write_text(text)
    study = load_study(path)
    assert [c.params.hub_bolts.count for c in study.candidates()] == [4, 8]
    assert [c.name for c in study.candidates()][0] == "hub bolts count 4 x 3 beams x 8 mm"
    both = tmp_path / "both.toml"
    both.write_text(path.read_text().replace("[design_space]\n", "[design_space]\nhub_radius_mm = [13.0, 14.0]\n"))
    with pytest.raises(ConfigError, match="design_space.hub_radius_mm is also fixed as geometry.hub_radius_mm"):
        load_study(both)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text(path.read_text().replace("[design_space]\n", "[design_space]\nclockwise = [true, false]\n"))
    with pytest.raises(ConfigError, match="design_space.clockwise is not a numeric geometry key"):
        load_study(unknown)
    bad = tmp_path / "bad.toml"
    bad.write_text(path.read_text().replace('"hub_bolts.count" = [4, 8]', '"hub_bolts.count" = [4, 0]'))
    with pytest.raises(ConfigError, match=r"design_space.hub_bolts.count\[1\] must be >= 1"):
        load_study(bad)


def test_solve_and_export_pick_a_candidate_by_any_axis(tmp_path):
    path = thickness_study(tmp_path)
    result = CliRunner().invoke(main, ["export", str(path), "--param", "thickness_mm=12", "--out", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "o" / "axial" / "thickness12mm.step").is_file()
    result = CliRunner().invoke(main, ["export", str(path), "--param", "thickness_mm=10", "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and "thickness_mm = 10 is not in study 'axial'" in result.output
    result = CliRunner().invoke(main, ["export", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2 and "--param KEY=VALUE for each design axis of 'axial': thickness_mm" in result.output


def test_ranges_continuous_bounds_and_a_material_axis(tmp_path):
    text = _study_text(arc_radius_mm="", material="", beam_thickness_mm="beam_thickness_mm = [6.0]",
                       beam_count='beam_count = {min = 3, max = 7, step = 2}\narc_radius_mm = {min = 4.5, max = 6.0}\n'
                                  'material = ["ninjaflex", "cheetah"]')
    path = tmp_path / "mixed.toml"
    path.write_text(text)
    study = load_study(path)
    axes = {a.key: a for a in study.axes}
    assert axes["beam_count"].values == (3, 5, 7)
    assert axes["arc_radius_mm"].continuous and axes["arc_radius_mm"].bounds == (4.5, 6.0)
    assert axes["material"].values == ("ninjaflex", "cheetah")
    with pytest.raises(ConfigError, match="continuous axes"):
        study.candidates()
    c = study.candidate(arc_radius_mm=5.123456789, beam_count=5, beam_thickness_mm=6.0, material="cheetah")
    assert c.params.arc_radius_mm == 5.123456789  # exact in the geometry (and so in every cache key)
    assert "arc radius 5.12 mm" in c.name and "cheetah" in c.name  # rounded to 0.01 mm in the name
    assert c.material.name.startswith("NinjaTek Cheetah")
    checked, _ = study.check(c)
    assert checked.mass_kg == pytest.approx(checked.volume_mm3 * 1e-9 * 1220.0, rel=1e-12)  # Cheetah's density
    with pytest.raises(ConfigError, match=r"arc_radius_mm = 6.5 is not in study .*arc_radius_mm in \[4.5, 6\]"):
        study.candidate(arc_radius_mm=6.5, beam_count=5, beam_thickness_mm=6.0, material="cheetah")
    with pytest.raises(ConfigError, match="material as a design axis"):
        study.material
