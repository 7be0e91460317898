"""What an install carries: the version agrees everywhere, and the wheel holds every package, the studies, the
materials and the licence. (CI also installs the wheel into a fresh environment and runs it: .ci/run.)"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

from click.testing import CliRunner

from seadesign.cli import main

REPO = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())


def test_the_version_agrees_in_pyproject_the_command_and_the_changelog():
    version = PYPROJECT["project"]["version"]
    shown = CliRunner().invoke(main, ["--version"]).output
    assert shown == f"seadesign, version {version}\n", (
        f"pyproject says {version}, `seadesign --version` {shown!r} (from the installed metadata): "
        "reinstall (pip install -e .) after changing the version")
    released = re.search(r"^## \[(\d+\.\d+\.\d+)\]", (REPO / "CHANGELOG.md").read_text(), flags=re.M)
    assert released is not None and released.group(1) == version, "CHANGELOG.md's top released entry is not " + version


def test_the_package_list_names_every_package_folder():
    folders = {".".join(p.relative_to(REPO).parts) for p in (REPO / "seadesign").rglob("*")
               if p.is_dir() and p.name != "__pycache__"}
    mapped = PYPROJECT["tool"]["setuptools"]["package-dir"]
    assert set(PYPROJECT["tool"]["setuptools"]["packages"]) == {"seadesign", *folders, *mapped}
    assert all((REPO / folder).is_dir() for folder in mapped.values())


def test_the_wheel_carries_the_studies_the_materials_and_the_licence(tmp_path):
    source = tmp_path / "source"  # a copy, so the build leaves nothing in the checkout
    source.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(REPO / name, source / name)
    for folder in ("seadesign", "studies", "materials"):
        shutil.copytree(REPO / folder, source / folder, ignore=shutil.ignore_patterns("__pycache__"))
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "-q", "-w", str(tmp_path)],
                           capture_output=True, text=True, timeout=600)
    assert build.returncode == 0, build.stdout + build.stderr
    (wheel,) = tmp_path.glob("seadesign-*.whl")
    archive = zipfile.ZipFile(wheel)
    names = set(archive.namelist())
    for folder in ("studies", "materials"):
        shipped = {f"seadesign/{folder}/{p.name}" for p in (REPO / folder).glob("*.toml")}
        assert shipped and shipped <= names, sorted(shipped - names)
    assert "seadesign/design/schemas/spring.schema.json" in names
    version = PYPROJECT["project"]["version"]
    assert archive.read(f"seadesign-{version}.dist-info/licenses/LICENSE") == (REPO / "LICENSE").read_bytes()
    assert "License-Expression: MIT" in archive.read(f"seadesign-{version}.dist-info/METADATA").decode()
    assert {p.relative_to(REPO).as_posix() for p in (REPO / "seadesign").rglob("*.py")} <= names
