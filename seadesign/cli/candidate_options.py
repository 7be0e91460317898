"""Choosing one candidate of a study on the command line: `--param KEY=VALUE` per design axis,
with `--beams N` and `--thickness-mm T` as short forms of the thesis's two axes."""

from __future__ import annotations

import click

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.errors import ConfigError

SHORT_FORMS = {"beams": "beam_count", "thickness_mm": "beam_thickness_mm"}


def candidate_options(command):
    """Add --beams, --thickness-mm and --param to a command (they arrive as `beams`, `thickness_mm`, `param`)."""
    command = click.option("--param", "param", multiple=True, metavar="KEY=VALUE",
                           help="Value of one design axis of the study (repeat for each axis), e.g. "
                                "--param thickness_mm=12; lengths in mm as the key says.")(command)
    command = click.option("--thickness-mm", type=float, help="Short for --param beam_thickness_mm=T (mm).")(command)
    return click.option("--beams", type=int, help="Short for --param beam_count=N.")(command)


def pick_candidate(study: Study, beams: int | None, thickness_mm: float | None, param: tuple[str, ...]) -> Candidate:
    """The study's candidate with the given axis values; a clear error names what is missing or wrong."""
    given: dict[str, float | int] = {key: v for name, key in SHORT_FORMS.items()
                                     if (v := {"beams": beams, "thickness_mm": thickness_mm}[name]) is not None}
    for text in param:
        key, sep, value = text.partition("=")
        try:
            given[key.strip()] = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except ValueError:
            raise ConfigError(f"--param {text!r}: give KEY=VALUE with a number, e.g. --param thickness_mm=12") from None
        if not sep:
            raise ConfigError(f"--param {text!r}: give KEY=VALUE, e.g. --param thickness_mm=12")
    axes = [a.key for a in study.axes]
    missing = [k for k in axes if k not in given]
    if missing:
        short = "--beams N and --thickness-mm T (or " if set(axes) == set(SHORT_FORMS.values()) else ""
        raise ConfigError(f"the study form needs {short}--param KEY=VALUE for each design axis of '{study.name}': "
                          f"{', '.join(axes)}{')' if short else ''}; missing: {', '.join(missing)}")
    return study.candidate(**given)
