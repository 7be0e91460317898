"""One part on its own: the linear solve of a study candidate or of an STL with its exports (what
`seadesign solve` prints), and a candidate's large-deflection torque path exactly as the sweep computes it
(the sweep's path mesh, `SolverSettings`, the stage cache), as a table and a plot.

Lengths in mm where named, otherwise SI (N, Nm, rad, Pa).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from seadesign.design.candidate import Candidate
from seadesign.design.study import Study
from seadesign.errors import ConfigError
from seadesign.run.cache import Cache, default_cache
from seadesign.sweep.path_stage import PathResponse, path_response
from seadesign.sweep.stages import SolverSettings, check_geometry, part_source

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

    from seadesign.design.materials import Material
    from seadesign.fea.large_deflection import LargeDeflection


@dataclass(frozen=True)
class LinearSolve:
    """What one linear solve of both load cases gave and how it was meshed.

    Attributes
    ----------
    name : str
        The part's name (the candidate's file stem, or the STL's stem); the files are named after it.
    results : dict
        Both load cases at their torques (`fea.results` columns, units in the names, e.g. `k_Nm_per_rad`),
        and the wall times `time_mesh_s`, `time_total_s`.
    material : Material
        The material solved (its name and sources; the moduli given as overrides are in `results`' inputs).
    backend : str
        The mesher, "gmsh" or "pytetwild".
    elements_across_beam : float
        Mesh density: elements across the beam width.
    beam_width_mm : float
        The beam width (mm) that sets the element size.
    elements_per_circle : float
        gmsh: elements per full turn on curved surfaces (0: uniform).
    files : tuple of Path
        The results JSON and the VTU fields written (empty when no folder was given).
    """

    name: str
    results: dict
    material: Material
    backend: str
    elements_across_beam: float
    beam_width_mm: float
    elements_per_circle: float
    files: tuple[Path, ...]

    @property
    def k_Nm_per_rad(self) -> float:
        """The spring constant k at rest (Nm/rad)."""
        return float(self.results["k_Nm_per_rad"])


@dataclass(frozen=True)
class _Loads:
    """Material values and torques of a solve, each the given override or the study's."""

    youngs_modulus_Pa: float
    poisson_ratio: float
    yield_strength_Pa: float
    stall_torque_Nm: float
    impact_torque_Nm: float


def _loads(study: Study, material: Material, youngs_modulus_Pa: float | None, poisson_ratio: float | None,
           yield_strength_Pa: float | None, stall_torque_Nm: float | None, impact_torque_Nm: float | None) -> _Loads:
    return _Loads(youngs_modulus_Pa or material.youngs_modulus_Pa,
                  poisson_ratio if poisson_ratio is not None else material.poisson_ratio,
                  yield_strength_Pa or material.yield_strength_Pa,
                  stall_torque_Nm or study.load_cases.stall_torque_Nm,
                  impact_torque_Nm or study.load_cases.impact_torque_Nm)


def _solve(geometry, interfaces, name: str, material: Material, loads: _Loads, bearing_radius_mm: float,
           across: float, width_mm: float, backend: str, per_circle: float, layers: int, out_dir: Path | None,
           export_ccx_dir: Path | None) -> LinearSolve:
    from seadesign.fea.solve_part import solve_part

    results, _, _ = solve_part(
        geometry, interfaces, youngs_modulus_Pa=loads.youngs_modulus_Pa, poisson_ratio=loads.poisson_ratio,
        yield_strength_Pa=loads.yield_strength_Pa, stall_torque_Nm=loads.stall_torque_Nm,
        impact_torque_Nm=loads.impact_torque_Nm, bearing_radius_mm=bearing_radius_mm, elements_across_beam=across,
        beam_width_mm=width_mm, backend=backend, elements_per_circle=per_circle, layers=layers, out_dir=out_dir,
        export_ccx_dir=export_ccx_dir, name=name)
    files = () if out_dir is None else (Path(out_dir) / f"{name}.json", Path(out_dir) / f"{name}.vtu")
    return LinearSolve(name, results, material, backend, across, width_mm, per_circle, files)


def solve_candidate(study: Study, candidate: Candidate, *, out_dir: str | Path | None = None,
                    material: str | Path | None = None, youngs_modulus_Pa: float | None = None,
                    poisson_ratio: float | None = None, yield_strength_Pa: float | None = None,
                    stall_torque_Nm: float | None = None, impact_torque_Nm: float | None = None,
                    bearing_radius_mm: float | None = None, elements_across_beam: float | None = None,
                    elements_per_circle: float | None = None, backend: str | None = None,
                    export_ccx_dir: str | Path | None = None) -> LinearSolve:
    """Mesh one study candidate and solve both linear load cases (stall and impact), as `seadesign solve STUDY`.

    Parameters
    ----------
    study : Study
        The study the candidate belongs to (its loads, mesh settings and bearing radius are the defaults).
    candidate : Candidate
        The candidate, e.g. ``study.candidate(beam_count=3, beam_thickness_mm=8.0)``.
    out_dir : str or Path, optional
        Folder for ``<name>.json`` and ``<name>.vtu``; None writes nothing.
    material : str or Path, optional
        Another material (a name or a TOML path); default: the candidate's.
    youngs_modulus_Pa, poisson_ratio, yield_strength_Pa : float, optional
        Overrides of the material's Young's modulus (Pa), Poisson ratio (-) and yield strength (Pa).
    stall_torque_Nm, impact_torque_Nm : float, optional
        Load-case torques (Nm); default: the study's.
    bearing_radius_mm : float, optional
        Radius (mm) on which the stall displacement is read; default: the study's.
    elements_across_beam : float, optional
        Mesh density (elements across the beam width); default: the study's.
    elements_per_circle : float, optional
        gmsh: elements per full turn on curved surfaces; default: the study's (0 with pytetwild).
    backend : {"gmsh", "pytetwild"}, optional
        The mesher; default: the study's.
    export_ccx_dir : str or Path, optional
        Also write the CalculiX decks ``stall.inp`` and ``impact.inp`` here.

    Returns
    -------
    LinearSolve
        The results (units in the keys, e.g. ``k_Nm_per_rad``), the mesh settings used and the files written.

    Raises
    ------
    ConfigError
        The candidate is not printable (the reasons are named), or a material is not found.
    MeshError, SolverError
        Meshing or the solve failed (the message names the setting to change).

    Examples
    --------
    >>> import seadesign as sd
    >>> study = sd.load_study("wolfgang_knee")
    >>> sd.solve(study, study.candidate(beam_count=3, beam_thickness_mm=8.0)).k_Nm_per_rad
    """
    from seadesign.design.materials import load_material

    checked, part = study.check(candidate)
    if not checked.valid:
        raise ConfigError(f"candidate {checked.name} is invalid: {'; '.join(checked.reasons)}")
    mat = load_material(material) if material else checked.material
    mesher = backend or study.mesh.backend
    per_circle = elements_per_circle if elements_per_circle is not None else (
        study.mesh.elements_per_circle if mesher == "gmsh" else 0.0)
    layers = study.mesh.mesh_part_options()["layers"] if mesher == "gmsh" else 0
    loads = _loads(study, mat, youngs_modulus_Pa, poisson_ratio, yield_strength_Pa, stall_torque_Nm, impact_torque_Nm)
    return _solve(part.solid, part.interfaces, checked.stem, mat, loads, bearing_radius_mm or study.bearing_radius_mm,
                  elements_across_beam or study.mesh.elements_across_beam, checked.params.beam_thickness_mm, mesher,
                  per_circle, layers, out_dir, export_ccx_dir)


def solve_stl(stl: str | Path, beam_width_mm: float, *, study: Study | None = None, axis: str = "y",
              out_dir: str | Path | None = None, material: str | Path = "ninjaflex",
              youngs_modulus_Pa: float | None = None, poisson_ratio: float | None = None,
              yield_strength_Pa: float | None = None, stall_torque_Nm: float | None = None,
              impact_torque_Nm: float | None = None, bearing_radius_mm: float | None = None,
              elements_across_beam: float = 3.0, elements_per_circle: float = 0.0, backend: str = "pytetwild",
              export_ccx_dir: str | Path | None = None) -> LinearSolve:
    """Mesh a spring given as an STL and solve both linear load cases, as `seadesign solve --stl`.

    Parameters
    ----------
    stl : str or Path
        The part's STL (mm); its hub and ring interfaces are detected.
    beam_width_mm : float
        The beams' in-plane width (mm); it sets the element size.
    study : Study, optional
        Whose torques are the defaults; None: the default study's.
    axis : {"x", "y", "z"}
        The spring's axis in the STL.
    out_dir : str or Path, optional
        Folder for ``<stem>.json`` and ``<stem>.vtu``; None writes nothing.
    material : str or Path
        Material name or TOML path.
    youngs_modulus_Pa, poisson_ratio, yield_strength_Pa : float, optional
        Overrides of the material's Young's modulus (Pa), Poisson ratio (-) and yield strength (Pa).
    stall_torque_Nm, impact_torque_Nm : float, optional
        Load-case torques (Nm); default: the study's.
    bearing_radius_mm : float, optional
        Radius (mm) on which the stall displacement is read; default: the detected hub radius.
    elements_across_beam : float
        Mesh density (elements across `beam_width_mm`).
    elements_per_circle : float
        gmsh: elements per full turn on curved surfaces (0: uniform).
    backend : {"pytetwild", "gmsh"}
        The mesher.
    export_ccx_dir : str or Path, optional
        Also write the CalculiX decks ``stall.inp`` and ``impact.inp`` here.

    Returns
    -------
    LinearSolve
        The results (units in the keys), the mesh settings used and the files written.

    Raises
    ------
    MeshError
        The STL cannot be read or meshed, or its interfaces are not found.
    ConfigError
        The material is not found.

    Examples
    --------
    >>> import seadesign as sd
    >>> sd.solve_stl("spring.stl", beam_width_mm=8.0).k_Nm_per_rad
    """
    from seadesign.design.materials import load_material
    from seadesign.design.study import load_study
    from seadesign.mesh import load_stl
    from seadesign.mesh.detect import detect_interfaces

    study = study or load_study()
    geometry = load_stl(stl, axis)
    interfaces = detect_interfaces(*geometry)
    mat = load_material(material)
    loads = _loads(study, mat, youngs_modulus_Pa, poisson_ratio, yield_strength_Pa, stall_torque_Nm, impact_torque_Nm)
    return _solve(geometry, interfaces, Path(stl).stem, mat, loads, bearing_radius_mm or interfaces.hub_radius_mm,
                  elements_across_beam, beam_width_mm, backend, elements_per_circle, 0, out_dir, export_ccx_dir)


@dataclass(frozen=True)
class CandidatePath:
    """A candidate's large-deflection torque path from rest to where it stopped, read at the study's loads.

    Attributes
    ----------
    study : Study
        The study whose loads and strain limits the path is read against.
    candidate : Candidate
        The checked candidate.
    response : PathResponse
        The sweep stage's output (`sweep.path_stage`): the path read at the loads, and the rendered state.
    """

    study: Study
    candidate: Candidate
    response: PathResponse

    @property
    def result(self) -> LargeDeflection:
        """The path read at the standing, stall and impact torques (`fea.large_deflection.LargeDeflection`)."""
        return self.response.result

    @property
    def stop_reason(self) -> str:
        """Why the path stopped (``target_reached``, ``contact``, ``limit_point``, ``bifurcation``, ...)."""
        return self.result.stop_reason

    @property
    def stop_rotation_rad(self) -> float:
        """Hub rotation (rad) where the path stopped."""
        return self.result.stop_rotation_rad

    @property
    def stop_torque_Nm(self) -> float:
        """Hub torque (Nm) where the path stopped."""
        return self.result.stop_torque_Nm

    def to_frame(self) -> pd.DataFrame:
        """The path's converged points as a table.

        Returns
        -------
        pandas.DataFrame
            One row per point from rest: ``rotation_rad``, ``rotation_deg``, ``torque_Nm`` and the tangent
            ``tangent_Nm_per_rad`` (dT/dtheta).

        Examples
        --------
        >>> path.to_frame()["torque_Nm"].max()
        """
        import numpy as np
        import pandas as pd

        rotation = np.asarray(self.result.curve_rotation_rad, float)
        return pd.DataFrame({"rotation_rad": rotation, "rotation_deg": np.degrees(rotation),
                             "torque_Nm": np.asarray(self.result.curve_torque_Nm, float),
                             "tangent_Nm_per_rad": np.asarray(self.result.curve_tangent_Nm_per_rad, float)})

    def plot(self, ax: Axes | None = None) -> Axes:
        """Torque (Nm) against hub rotation (rad), the stop marked with its reason, the stall and impact torques
        as dashed lines.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Where to draw; None: a new figure.

        Returns
        -------
        matplotlib.axes.Axes
            The axes drawn on.

        Examples
        --------
        >>> path.plot().figure.savefig("path.png")
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6, 4.5))
        t = self.to_frame()
        ax.plot(t["rotation_rad"], t["torque_Nm"], "-", label=self.candidate.name)
        ax.plot(self.stop_rotation_rad, self.stop_torque_Nm, "x", ms=9, mew=2, color="r",
                label=f"stop: {self.stop_reason}")
        lc = self.study.load_cases
        for torque_Nm, name in ((lc.stall_torque_Nm, "stall"), (lc.impact_torque_Nm, "impact")):
            ax.axhline(torque_Nm, color="k", ls="--", lw=0.8)
            ax.annotate(f"{name} {torque_Nm:.3g} Nm", (0, torque_Nm), fontsize=7, xytext=(2, 2),
                        textcoords="offset points")
        ax.set(xlabel="hub rotation (rad)", ylabel="torque (Nm)", title=f"Torque path of {self.candidate.name}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        return ax


def candidate_path(study: Study, candidate: Candidate, *, settings: SolverSettings = SolverSettings(),
                   cache: Cache | None = None) -> CandidatePath:
    """A candidate's large-deflection torque path as the sweep computes it: on the sweep's path mesh
    (`SolverSettings.path_layers` layers through the thickness), from the stage cache when it is there.

    Parameters
    ----------
    study : Study
        The study the candidate belongs to (its torques, strain limits and mesh sizing).
    candidate : Candidate
        The candidate, e.g. ``study.candidate(beam_count=3, beam_thickness_mm=8.0)``.
    settings : SolverSettings
        The sweep's numerical settings (element order, path mesh layers, formulation).
    cache : Cache, optional
        The stage cache; None: the one the CLI uses ($SEADESIGN_CACHE, else ~/.cache/seadesign).

    Returns
    -------
    CandidatePath
        The path (``to_frame()``, ``plot()``) and its reading at the loads (``result``).

    Raises
    ------
    ConfigError
        The candidate is not printable (the reasons are named).
    MeshError, SolverError
        Meshing or the path's solve failed.

    Examples
    --------
    >>> import seadesign as sd
    >>> study = sd.load_study("wolfgang_knee")
    >>> path = sd.torque_path(study, study.candidate(beam_count=3, beam_thickness_mm=8.0))
    >>> path.stop_reason, path.stop_torque_Nm
    """
    cache = cache or default_cache()
    checked, part = check_geometry(study, candidate, cache)
    if not checked.valid:
        raise ConfigError(f"candidate {checked.name} is invalid: {'; '.join(checked.reasons)}")
    response = path_response(study, checked, part_source(study, checked, part, _quiet), settings, cache, _quiet)
    return CandidatePath(study, checked, response)


def _quiet(stage: str) -> None:
    """A progress hook that shows nothing."""
