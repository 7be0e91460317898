"""A tiny study for sweep tests: one valid candidate (3 beams x 8 mm, coarse mesh) and one
invalid one (10 beams x 8 mm: beams touch), derived from the default study file."""

from __future__ import annotations

import re
from pathlib import Path

from seadesign.design.study import DEFAULT_STUDY


def write_tiny_study(folder: Path, name: str = "tiny", **replace: str) -> Path:
    """The default study with a two-candidate design space and a coarse mesh; `replace` maps a
    key to its new TOML value text (first occurrence)."""
    text = DEFAULT_STUDY.read_text()
    values = {"name": f'"{name}"', "beam_count": "[3, 10]", "beam_thickness_mm": "[8.0]",
              "elements_across_beam": "0.6", "elements_per_circle": "0", "layers": "2", **replace}
    for key, value in values.items():
        text, n = re.subn(rf"(?m)^{key}\s*=\s*[^#\n]*", f"{key} = {value}  ", text, count=1)
        assert n == 1, key
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path
