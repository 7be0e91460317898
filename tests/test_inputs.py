"""Study and material files: packaged with seadesign, a working-directory file or a path taking precedence,
the files used recorded with their hashes, and `seadesign init`'s files to start from."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest
from click.testing import CliRunner

from seadesign.cli import main
from seadesign.design.inputs import MATERIAL, STUDY
from seadesign.design.materials import load_material
from seadesign.design.study import DEFAULT_STUDY, load_study
from seadesign.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_a_source_tree_reads_the_top_level_folders():
    assert STUDY.packaged == REPO / "studies" and MATERIAL.packaged == REPO / "materials"
    assert DEFAULT_STUDY == REPO / "studies" / "wolfgang_knee.toml"


def test_the_study_and_material_files_are_recorded_with_their_hashes():
    files = load_study("bitbots_shoulder").files
    assert files.study.path == REPO / "studies" / "bitbots_shoulder.toml"
    assert files.study.sha256 == _sha256(files.study.path)
    nf = files.materials["ninjaflex"]
    assert nf.path == REPO / "materials" / "ninjaflex.toml" and nf.sha256 == _sha256(nf.path)
    assert f"material ninjaflex {nf.path} (sha256 {nf.sha256})" in files.describe()


def test_a_file_in_the_working_directory_takes_precedence(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = (MATERIAL.packaged / "ninjaflex.toml").read_text()
    (tmp_path / "ninjaflex.toml").write_text(text.replace('name = "NinjaFlex TPU 85A"', 'name = "Local TPU"'))
    study_text = DEFAULT_STUDY.read_text().replace('description = "', 'description = "local: ', 1)
    (tmp_path / "wolfgang_knee.toml").write_text(study_text)
    assert load_material("ninjaflex").name == "Local TPU"
    s = load_study("wolfgang_knee")
    assert s.description.startswith("local: ") and s.material.name == "Local TPU"
    assert s.files.study.path == tmp_path / "wolfgang_knee.toml"
    assert s.files.materials["ninjaflex"].sha256 == _sha256(tmp_path / "ninjaflex.toml")
    assert load_study("bitbots_shoulder").files.study.path == REPO / "studies" / "bitbots_shoulder.toml"
    assert load_study(DEFAULT_STUDY).files.study.path == DEFAULT_STUDY  # a path is read as given


def test_an_unknown_name_lists_both_places(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_spring.toml").write_text("")
    with pytest.raises(ConfigError) as err:
        load_study("nosuch")
    message = str(err.value)
    assert f"no nosuch.toml in the working directory {tmp_path} (its .toml files: my_spring.toml)" in message
    assert f"nor among the packaged studies in {REPO / 'studies'} (bitbots_shoulder, wolfgang_knee," in message
    with pytest.raises(ConfigError, match=r"material file .*nosuch\.toml not found; check the path"):
        load_material(tmp_path / "nosuch.toml")


def test_init_writes_files_to_start_from_that_commands_there_read_first(tmp_path, monkeypatch):
    runner = CliRunner()
    result = runner.invoke(main, ["init", str(tmp_path / "knee")])
    assert result.exit_code == 0, result.output
    study, material = tmp_path / "knee" / "wolfgang_knee.toml", tmp_path / "knee" / "ninjaflex.toml"
    assert study.read_text().startswith("# A study to start from, written by `seadesign init`")
    assert study.read_text().endswith(DEFAULT_STUDY.read_text())
    assert material.read_text().endswith((MATERIAL.packaged / "ninjaflex.toml").read_text())
    again = runner.invoke(main, ["init", str(tmp_path / "knee")])
    assert again.exit_code == 2 and f"{study} and {material} already exist" in again.output
    assert "--force" in again.output and "Traceback" not in again.output
    study.write_text(study.read_text().replace("beam_count = [3, 4, 5, 6, 7, 8, 9, 10]", "beam_count = [3, 4]"))
    material.write_text(material.read_text().replace('name = "NinjaFlex TPU 85A"', 'name = "My TPU"'))
    monkeypatch.chdir(tmp_path / "knee")
    listed = runner.invoke(main, ["geometry", "wolfgang_knee"])
    assert listed.exit_code == 0, listed.output
    assert listed.output.startswith("study wolfgang_knee: 6 candidates, material My TPU\n")
    forced = runner.invoke(main, ["init", "--force"])
    assert forced.exit_code == 0 and "beam_count = [3, 4, 5, 6, 7, 8, 9, 10]" in study.read_text()
