"""Where study and material files are found, and the record of the files a result was computed from.

Studies and materials ship inside the package: an installed wheel holds them as package data
(`seadesign/studies`, `seadesign/materials`, mapped from the repository's top-level `studies/` and `materials/`
by pyproject's `package-dir`); a source tree, installed editable or not, reads those top-level folders.
A name (a file stem) is looked up in the working directory first, then among the packaged files; a path
(ending in .toml) is read as given.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from seadesign.errors import ConfigError

SOURCE_TREE = Path(__file__).resolve().parents[2]  # the repository root when running from a checkout


@dataclass(frozen=True)
class Kind:
    """A kind of input file: its name in messages and its folder of packaged files."""

    name: str  # "study"
    folder: str  # "studies"

    @property
    def packaged(self) -> Path:
        """The packaged files: the installed package data, else the source tree's top-level folder."""
        installed = resources.files("seadesign").joinpath(self.folder)
        return Path(str(installed)) if installed.is_dir() else SOURCE_TREE / self.folder

    def find(self, name_or_path: str | Path) -> Path:
        """A file by path (ending in .toml), or by name: NAME.toml in the working directory, else packaged."""
        path = Path(name_or_path)
        if path.suffix == ".toml":
            if not path.is_file():
                raise ConfigError(f"{self.name} file {path} not found; check the path")
            return path
        here, packaged = Path.cwd(), self.packaged
        for folder in (here, packaged):
            if (folder / f"{name_or_path}.toml").is_file():
                return folder / f"{name_or_path}.toml"
        here_files = ", ".join(sorted(p.name for p in here.glob("*.toml"))) or "none"
        known = ", ".join(sorted(p.stem for p in packaged.glob("*.toml"))) or "none"
        raise ConfigError(f"{self.name} '{name_or_path}' not found: no {name_or_path}.toml in the working directory "
                          f"{here} (its .toml files: {here_files}) nor among the packaged {self.folder} in {packaged} "
                          f"({known}); give one of these names or a path to a .toml file "
                          "('seadesign init' writes a study and a material to start from)")


STUDY = Kind("study", "studies")
MATERIAL = Kind("material", "materials")


@dataclass(frozen=True)
class InputFile:
    """A file a result was computed from: its absolute path and the SHA-256 of its bytes."""

    path: Path
    sha256: str

    @classmethod
    def of(cls, path: Path) -> "InputFile":
        return cls(path.resolve(), hashlib.sha256(path.read_bytes()).hexdigest())

    def describe(self) -> str:
        return f"{self.path} (sha256 {self.sha256})"


@dataclass(frozen=True)
class StudyFiles:
    """The study file and the material files a study was loaded from (materials by the study's name for them)."""

    study: InputFile
    materials: dict[str, InputFile]

    def describe(self) -> str:
        """Every file with its hash, in words."""
        return "; ".join([f"study {self.study.describe()}",
                          *(f"material {name} {f.describe()}" for name, f in self.materials.items())])
