"""The design side of ``import seadesign as sd``: loading a study or a material, a candidate's CAD part and
printability, and its STL/STEP export, with the command line's defaults. The other entry points live
with the pipelines they run (see `seadesign`).

Lengths in mm where named, otherwise SI (N, Nm, rad, Pa).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from seadesign.errors import ConfigError

if TYPE_CHECKING:
    from seadesign.design.candidate import Candidate
    from seadesign.design.geometry import Part
    from seadesign.design.materials import Material
    from seadesign.design.study import Study

#: the study the commands use when none is named
DEFAULT_STUDY_NAME = "wolfgang_knee"


def load_study(study: str | Path = DEFAULT_STUDY_NAME) -> Study:
    """Load and check a study file; every key is validated before any work starts.

    Parameters
    ----------
    study : str or Path
        A name (``NAME.toml`` in the working directory, else the packaged study) or a path.

    Returns
    -------
    Study
        The design space (``study.axes``, ``study.candidates()``, ``study.candidate(...)``), the loads, the
        robot, the materials, the mesh settings, the requirements and their stiffness window
        (``study.k_window``).

    Raises
    ------
    ConfigError
        The file is missing or a key is wrong; the message names the file, the key and the fix.

    Examples
    --------
    >>> import seadesign as sd
    >>> study = sd.load_study("wolfgang_knee")
    >>> [axis.key for axis in study.axes]
    ['beam_count', 'beam_thickness_mm']
    """
    from seadesign.design.study import load_study as _load

    return _load(study)


def load_material(material: str | Path) -> Material:
    """Load and check a material file (moduli, strain limits and the hyperelastic law, each with its source).

    Parameters
    ----------
    material : str or Path
        A name (``NAME.toml`` in the working directory, else the packaged material) or a path.

    Returns
    -------
    Material
        Young's modulus (``youngs_modulus_Pa``), Poisson ratio, yield strength (Pa), density, the law, the sources.

    Raises
    ------
    ConfigError
        The file is missing or a key is wrong; the message names the file and the key.

    Examples
    --------
    >>> import seadesign as sd
    >>> sd.load_material("ninjaflex").youngs_modulus_Pa / 1e6
    12.0
    """
    from seadesign.design.materials import load_material as _load

    return _load(material)


def geometry(study: Study, candidate: Candidate) -> tuple[Candidate, Part]:
    """Build a candidate's CAD solid and check that it can be printed (the study's validity rules).

    Parameters
    ----------
    study : Study
        The study the candidate belongs to.
    candidate : Candidate
        The candidate, e.g. ``study.candidate(beam_count=3, beam_thickness_mm=8.0)``.

    Returns
    -------
    tuple of (Candidate, Part)
        The checked candidate (``valid``, ``reasons``, ``volume_mm3``, ``mass_kg``) and its part (the CadQuery
        solid and its hub and ring interfaces).

    Raises
    ------
    ConfigError
        The candidate's parameters cannot describe a part (the message names the key).

    Examples
    --------
    >>> import seadesign as sd
    >>> study = sd.load_study()
    >>> checked, part = sd.geometry(study, study.candidate(beam_count=10, beam_thickness_mm=8.0))
    >>> checked.valid
    False
    """
    return study.check(candidate)


def export(study: Study, candidate: Candidate, out_dir: str | Path = Path("exports"),
           tolerance_mm: float = 0.01) -> list[Path]:
    """Write the STL (checked on read-back) and STEP of one valid candidate, in mm, as `seadesign export`.

    Parameters
    ----------
    study : Study
        The study the candidate belongs to.
    candidate : Candidate
        The candidate, e.g. ``study.candidate(beam_count=3, beam_thickness_mm=8.0)``.
    out_dir : str or Path
        Output root; files go to ``out_dir/<study>/<candidate>.stl`` and ``.step``.
    tolerance_mm : float
        STL chordal tolerance (mm): the largest distance between the triangles and the true surface.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    ConfigError
        The candidate cannot be printed (the reasons are named).
    ExportError
        The STL failed its read-back check (not watertight, or its volume is off; the fix is named).

    Examples
    --------
    >>> import seadesign as sd
    >>> study = sd.load_study()
    >>> sd.export(study, study.candidate(beam_count=3, beam_thickness_mm=8.0), "exports")
    """
    from seadesign.design.export import export_candidate

    checked, part = study.check(candidate)
    if not checked.valid:
        raise ConfigError(f"candidate {checked.name} is invalid: {'; '.join(checked.reasons)}")
    return export_candidate(checked, part, Path(out_dir) / study.name, tolerance_mm)
