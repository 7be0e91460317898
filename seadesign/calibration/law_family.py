"""The spring's torque curve under trial material laws: what a bench curve says about the law beyond its scale.

A hyperelastic law's torque curve scales with its moduli (at inverse compressibilities), so the one thing a bench
curve adds to the stiffness scale is the law's shape: for Mooney-Rivlin the share of C01 in the initial shear
modulus mu = 2 (C10 + C01), for Yeoh the ratio C20 / C10. A `LawFamily` holds the large-deflection path of the
spring's own part (the study and candidate of spring.json, `spring_source`) at a few values of that parameter,
each at the material's mu and compressibility, and interpolates between them: quadratic (Lagrange) in the
parameter at each rotation, the curves being smooth in the law's parameters. Its error against full paths at the
midpoints is measured by `benchmarks/law_fit.py` (docs/validation/calibration.md); on a closed-form family the
interpolation is tested to be exact.

The paths come from the stage cache (the material's own one is the sweep's). spring.json is refused when its study
cannot be loaded, or when its candidate under the material's law no longer gives spring.json's torque curve (the
study, the material, the solver or the code changed since the sweep): the curve is compared point by point, which
checks the very numbers the fit starts from, for sweep and explorer springs alike.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from seadesign.design.candidate import Candidate
from seadesign.design.materials import Hyperelastic, Material
from seadesign.design.spring import TorqueCurve, torque_curve
from seadesign.design.study import Study, load_study
from seadesign.effects.base import Effect, Param
from seadesign.errors import ConfigError
from seadesign.calibration.table import LoopData, LoopInputError
from seadesign.run.executors import default_jobs, run_processes, run_serial
from seadesign.sweep.handoff import curve_to_stop
from seadesign.sweep.single import CandidatePath, candidate_path

#: the law families a bench curve is fitted with: model -> (shape parameter, its nodes, what it is)
FAMILIES: dict[str, tuple[str, tuple[float, ...], str]] = {
    "mooney_rivlin": ("c01_share", (0.0, 0.4, 0.8), "C01 / (C10 + C01), at the material's mu = 2 (C10 + C01)"),
    "yeoh": ("c20_ratio", (-0.1, 0.0, 0.1), "C20 / C10, at the material's mu = 2 C10"),
}
#: the peak tensile strain below which a bench curve does not tell the laws' shapes apart (the second parameter acts
#: through the strain's square and beyond; about 20 % in the part's most strained fillet)
SHAPE_STRAIN = 0.20
#: relative difference (of the end torque) from which spring.json's curve is not its candidate's path any more
SAME_CURVE = 1e-6


class SpringSourceError(LoopInputError):
    """spring.json's part cannot be recomputed (its study is missing or changed): its law cannot be fitted."""


def trial_law(base: Hyperelastic, model: str, value: float) -> Hyperelastic:
    """The law of `model` ("mooney_rivlin", "yeoh") with shape parameter `value` (`FAMILIES`), at the initial shear
    modulus and compressibility of `base` (a neo-Hookean law, or one of `model`'s own)."""
    if base.model not in ("neo_hooke", model):
        raise SpringSourceError(f"the material's law is {base.model}; a {model} fit starts from a neo-Hookean law or "
                                f"a {model} one")
    half_mu = base.shear_modulus_Pa / 2.0
    if model == "mooney_rivlin":
        return Hyperelastic("mooney_rivlin", c10_Pa=(1.0 - value) * half_mu, c01_Pa=value * half_mu,
                            d1_per_Pa=base.d1_per_Pa, source=f"trial: C01 share {value:g} of mu")
    if model == "yeoh":
        return Hyperelastic("yeoh", c10_Pa=half_mu, c20_Pa=value * half_mu, c30_Pa=base.c30_Pa,
                            d1_per_Pa=base.d1_per_Pa, source=f"trial: C20 / C10 = {value:g}")
    raise SpringSourceError(f"unknown law family '{model}'; use one of {', '.join(FAMILIES)}")


def base_value(base: Hyperelastic, model: str) -> float:
    """The shape parameter of `model` that `base` itself has (0 for a neo-Hookean law)."""
    if model == "mooney_rivlin":
        return base.c01_Pa / (base.c10_Pa + base.c01_Pa)
    return base.c20_Pa / base.c10_Pa


@dataclass(frozen=True)
class SpringSource:
    """The study and the checked candidate that spring.json's spring is, and its path under the material's law."""

    study: Study
    candidate: Candidate
    path: CandidatePath

    def with_law(self, law: Hyperelastic) -> CandidatePath:
        """The candidate's path with the material's law replaced by `law` (from the stage cache when there)."""
        material: Material = replace(self.candidate.material, hyperelastic=law)
        return candidate_path(self.study, replace(self.candidate, material=material))


def path_curve(path: CandidatePath) -> TorqueCurve:
    """A path's torque curve as spring.json carries it (up to its stop, `sweep.handoff.curve_to_stop`)."""
    r = path.result
    rotation, torque = curve_to_stop({"large_curve_rotation_rad": r.curve_rotation_rad,
                                      "large_curve_torque_Nm": r.curve_torque_Nm,
                                      "large_stop_rotation_rad": r.stop_rotation_rad,
                                      "large_stop_torque_Nm": r.stop_torque_Nm})
    return TorqueCurve(tuple(rotation), tuple(torque), stop_reason=r.stop_reason)


def spring_source(spring: dict[str, Any]) -> SpringSource:
    """The study and candidate of spring.json, checked: its candidate under the material's law must give
    spring.json's torque curve. SpringSourceError with the reason otherwise (no curve, study not found, candidate
    not in the study, the curve changed)."""
    curve = torque_curve(spring)
    if curve is None:
        raise SpringSourceError("spring.json has no torque_curve (a linear spring): there is no large-deflection "
                                "path to fit a material law to")
    name = spring.get("study")
    try:
        study = load_study(name)
    except ConfigError as exc:
        raise SpringSourceError(f"spring.json's study '{name}' cannot be loaded ({exc}): its part cannot be "
                                f"recomputed for trial laws; run `seadesign explain` where the study is, or fit the "
                                f"scale alone (--law scale)") from None
    try:
        candidate = study.candidate_of(spring)
    except ConfigError as exc:
        raise SpringSourceError(f"spring.json's design is not a candidate of study '{name}' ({exc}): the study changed "
                                f"since the sweep; rerun `seadesign sweep {name}`") from None
    path = candidate_path(study, candidate)
    now = path_curve(path)
    end = max(abs(curve.torque_Nm[-1]), 1e-12)
    if len(now.torque_Nm) != len(curve.torque_Nm) or \
            np.max(np.abs(np.subtract(now.torque_Nm, curve.torque_Nm))) > SAME_CURVE * end or \
            np.max(np.abs(np.subtract(now.rotation_rad, curve.rotation_rad))) > SAME_CURVE * curve.rotation_rad[-1]:
        raise SpringSourceError(
            f"spring.json (inputs_hash {spring.get('inputs_hash', '?')}) no longer matches study '{name}': its "
            f"candidate {candidate.name} now ends at {now.torque_Nm[-1]:.4g} Nm, {now.rotation_rad[-1]:.4g} rad "
            f"({now.stop_reason}), spring.json's curve at {curve.torque_Nm[-1]:.4g} Nm, {curve.rotation_rad[-1]:.4g} "
            f"rad (the study, the material or the code changed since the sweep); rerun `seadesign sweep {name}`")
    return SpringSource(study, path.candidate, path)


@dataclass(frozen=True)
class LawFamily:
    """The spring's torque curve at a few values (`nodes`) of one law family's shape parameter, all at the material's
    initial shear modulus; `torque` interpolates between them."""

    model: str  # "mooney_rivlin" or "yeoh"
    parameter: str  # "c01_share" or "c20_ratio"
    base: Hyperelastic  # the material's law (its shape value is a node)
    base_value: float
    nodes: tuple[float, ...]
    curves: tuple[TorqueCurve, ...]
    strain_rotation_rad: tuple[float, ...]  # the material's path: rotation (rad) ...
    strain: tuple[float, ...]  # ... and the part's peak tensile engineering strain there

    @property
    def end_rad(self) -> float:
        """The rotation (rad) up to which every node's curve reaches."""
        return min(c.rotation_rad[-1] for c in self.curves)

    def weights(self, value: float) -> np.ndarray:
        """Lagrange weights of the nodes at `value`."""
        x = np.asarray(self.nodes, float)
        w = np.ones(x.size)
        for i in range(x.size):
            for j in range(x.size):
                if i != j:
                    w[i] *= (value - x[j]) / (x[i] - x[j])
        return w

    def torque(self, deflection_rad: np.ndarray, value: float) -> np.ndarray:
        """Torque (Nm) at `deflection_rad` (odd in it; held at the common end past it) for shape `value`."""
        d = np.asarray(deflection_rad, float)
        a = np.minimum(np.abs(d), self.end_rad)
        t = sum(w * c.torque(a) for w, c in zip(self.weights(value), self.curves))
        return np.sign(d) * t

    def law(self, value: float) -> Hyperelastic:
        """The family's law at shape `value`, at the material's modulus."""
        return trial_law(self.base, self.model, value)

    def strain_at(self, rotation_rad: float) -> float:
        """The part's peak tensile engineering strain at `rotation_rad` on the material's path (its end past it)."""
        return float(np.interp(abs(rotation_rad), self.strain_rotation_rad, self.strain))


def _trial_curve(task: tuple[Study, Candidate], sink) -> TorqueCurve:
    """A worker's task: the path's curve of a candidate whose material carries a trial law."""
    study, candidate = task
    return path_curve(candidate_path(study, candidate))


def law_families(source: SpringSource, models: tuple[str, ...]) -> dict[str, LawFamily]:
    """The families `models` (`FAMILIES`) of the spring of `source`: one path per node (the material's own law is
    the node at its shape value; the others in worker processes, two at a time on two cores, from the stage cache
    when there)."""
    base = source.candidate.material.law
    nodes = {}
    for model in models:
        b = base_value(base, model)
        nodes[model] = (b, tuple(sorted({*FAMILIES[model][1], b})))
    trials = [(m, v) for m, (b, vs) in nodes.items() for v in vs if v != b]
    tasks = [(source.study, replace(source.candidate, material=replace(source.candidate.material,
                                                                       hyperelastic=trial_law(base, m, v))))
             for m, v in trials]
    jobs = min(default_jobs(), len(tasks))
    run = run_serial(_trial_curve, tasks, lambda *_: None, lambda: None) if jobs <= 1 else \
        run_processes(_trial_curve, tasks, jobs, lambda *_: None, lambda: None, [])
    by_task = {id(task): curve for task, curve in run}
    curves = {trial: by_task[id(task)] for trial, task in zip(trials, tasks)}
    own = path_curve(source.path)
    r = source.path.result
    return {m: LawFamily(m, FAMILIES[m][0], base, b, vs, tuple(own if v == b else curves[(m, v)] for v in vs),
                         r.curve_rotation_rad, r.curve_tensile_strain)
            for m, (b, vs) in nodes.items()}


class LawShape(Effect):
    """The spring curve's shape under a law family (a loop candidate on a bench with a torque curve): torque +=
    s (T(d; v) - T(d; v0)), T the family's curve (`LawFamily.torque`), v0 the material's own value, s the curve's
    scale (the spring's term). Not a library effect: it needs the spring's own part (`law_family`)."""

    reads = ("deflection",)
    writes = "torque"

    def __init__(self, family: LawFamily, name: str | None = None, **options: Any) -> None:
        self.family = family
        super().__init__(name, **options)

    def replace(self, *, enabled: bool | None = None, **values: float) -> "LawShape":
        return type(self)(self.family, self.name, enabled=self.enabled if enabled is None else enabled,
                          **{**self.values, **values})

    def search(self, scales) -> tuple[dict[str, tuple[float, float]], list[dict[str, float]]]:
        p = self.parameters[0]
        return {p.name: (p.lower, p.upper)}, [{p.name: self.family.base_value}]

    def shape_torque(self, deflection_rad: np.ndarray, value: float) -> np.ndarray:
        """T(d; value) - T(d; v0) (Nm, before the curve's scale)."""
        f = self.family
        return f.torque(deflection_rad, value) - f.torque(deflection_rad, f.base_value)


def _param(model: str) -> Param:
    name, nodes, doc = FAMILIES[model]
    return Param(name, "1", 0.0, nodes[0], nodes[-1], doc)


class MooneyRivlinShape(LawShape):
    key = "mooney_rivlin"
    summary = "the spring curve of a Mooney-Rivlin law: C01's share of mu"
    parameters = (_param("mooney_rivlin"),)


class YeohShape(LawShape):
    key = "yeoh"
    summary = "the spring curve of a Yeoh law: C20 / C10"
    parameters = (_param("yeoh"),)


#: the law-shape loop candidates: key -> effect class
SHAPES: dict[str, type[LawShape]] = {"mooney_rivlin": MooneyRivlinShape, "yeoh": YeohShape}


def shape_coverage(family: LawFamily, data: LoopData) -> str:
    """Whether the measured deflections strain the part enough to tell the law's shape from its scale."""
    reach = float(np.max(np.abs(data.signals["deflection"][data.in_range])))
    strain = family.strain_at(reach)
    enough = strain >= SHAPE_STRAIN
    return (f"The bench file reaches {reach:.4g} rad on the curve, where the part's peak tensile strain is "
            f"{strain:.1%}; the law's shape (Mooney-Rivlin's C01 share, Yeoh's C20) shows in a torque curve only past "
            f"about {SHAPE_STRAIN:.0%}" + ("." if enough else ", which this file does not reach: it cannot identify "
                                        "the shape (a test to larger deflections can)."))


def bench_shapes(spring: dict[str, Any], data: LoopData, models: tuple[str, ...] = tuple(FAMILIES)) -> None:
    """Give a bench `data` (torque from deflection, with spring.json's torque curve) the law-shape candidates
    `models` of the spring's own part (`spring_source`, `law_families`) and the note on what the file covers."""
    families = law_families(spring_source(spring), models)
    data.shapes.update({m: SHAPES[m](f) for m, f in families.items()})
    data.notes.append(shape_coverage(next(iter(families.values())), data))
