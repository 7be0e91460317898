"""`seadesign init`: a study and a material to start from, copied from the packaged default study and its
material with a header saying what to edit."""

from __future__ import annotations

from pathlib import Path

from seadesign.design.inputs import MATERIAL
from seadesign.design.study import DEFAULT_STUDY
from seadesign.design.tomlcheck import read_toml
from seadesign.errors import ConfigError

STUDY_HEADER = """\
# A study to start from, written by `seadesign init` (a copy of the packaged study {name}).
# Edit it for your spring: name and description, the material (a material file's name; {material}.toml
# in this folder is read before the packaged one), the design axes under [design_space], the fixed dimensions
# under [geometry], and the robot, actuator, load cases and requirements. Run from this folder,
# `seadesign geometry {name}` reads this file before the packaged study of the same name; rename the file
# (and `name`) for a study of your own.

"""
MATERIAL_HEADER = """\
# A material to start from, written by `seadesign init` (a copy of the packaged material {name}).
# Edit the values, units and sources for your filament; every property needs its source. A study names it by
# the file name without .toml; run from this folder, that name reads this file before the packaged material.

"""


def write_starters(folder: Path, force: bool = False) -> list[Path]:
    """The default study and its material, with headers, in `folder`; existing files are refused unless `force`."""
    material = read_toml(DEFAULT_STUDY)["material"]
    sources = [(DEFAULT_STUDY, STUDY_HEADER), (MATERIAL.packaged / f"{material}.toml", MATERIAL_HEADER)]
    targets = [folder / source.name for source, _ in sources]
    existing = [str(t) for t in targets if t.exists()]
    if existing and not force:
        raise ConfigError(f"{' and '.join(existing)} already exist{'s' if len(existing) == 1 else ''}; "
                          "pass --force to overwrite, or choose another folder")
    folder.mkdir(parents=True, exist_ok=True)
    for (source, header), target in zip(sources, targets):
        target.write_text(header.format(name=source.stem, material=material) + source.read_text())
    return targets
