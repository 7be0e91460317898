"""The linear load cases' solve on the result mesh in double and in mixed precision: time, memory and agreement.

Usage: python benchmarks/linear_solve.py [--candidates 8x4,6x8,3x4] [--repeats 2] [--docs]
Per candidate: the condensed stiffness of the unit torsion problem on the study's result mesh (as
`fea.torsion.torsion_problem` assembles it), factored and solved by `fea.linsolve.SPDFactorization` in
double precision (PARDISO's Cholesky) and in mixed precision (single-precision factors preconditioning conjugate
gradients in double), alternated `--repeats` times in one process on the current MKL threads: the least time of
each, the largest growth of the resident memory while it runs (sampled every 10 ms; MKL holds the factors outside
Python's heap), the conjugate-gradient iterations, and the mixed solution's largest difference from the double one
relative to its largest entry (k: the hub's rotation).
"""

from __future__ import annotations

import argparse
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import psutil
from record import Table, add_docs_option, machine, write_fragment

from seadesign.design.study import load_study
from seadesign.fea.linsolve import SPDFactorization
from seadesign.fea.torsion import torsion_problem
from seadesign.run.cache import Cache
from seadesign.sweep.stages import REFERENCE_MODULUS_PA, tetrahedralize


class PeakMemory:
    """The largest growth of this process's resident memory (bytes) over a block, sampled every 10 ms."""

    def __enter__(self) -> PeakMemory:
        self._process = psutil.Process()
        self._start = self.peak = self._process.memory_info().rss
        self._running = True
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def _sample(self) -> None:
        while self._running:
            self.peak = max(self.peak, self._process.memory_info().rss)
            time.sleep(0.01)

    def __exit__(self, *exc) -> None:
        self._running = False
        self._thread.join()
        self.growth = self.peak - self._start


def solve(k, rhs, precision: str) -> tuple[float, int, int, np.ndarray]:
    """(seconds, resident memory growth in bytes, iterations, solution) of one factorization and solve."""
    with PeakMemory() as memory:
        t0 = time.perf_counter()
        f = SPDFactorization(k, precision=precision)
        x = f.solve(rhs)
        seconds = time.perf_counter() - t0
        f.close()
    return seconds, memory.growth, f.iterations, x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", default="8x4,6x8,3x4", help="beams x thickness (mm), comma-separated")
    ap.add_argument("--repeats", type=int, default=2)
    add_docs_option(ap, "linear_solve_precision")
    args = ap.parse_args()
    study = load_study()
    table = Table(["design", "dofs", "double: time (s), memory (GiB)", "mixed: time (s), memory (GiB), iterations",
                   "mixed against double: solution, k"])
    with tempfile.TemporaryDirectory() as d:
        for spec in args.candidates.split(","):
            n, t = spec.split("x")
            checked, part = study.check(study.candidate(beam_count=int(n), beam_thickness_mm=float(t)))
            mesh = tetrahedralize(study, checked, part, Cache(Path(d)))
            problem = torsion_problem(mesh, REFERENCE_MODULUS_PA, checked.material.poisson_ratio)
            k, rhs, rotation = problem.stiffness.matrix(), problem.unit_load(), problem.coupling.ref_dofs[5]
            runs = {"double": [], "mixed": []}
            for _ in range(args.repeats):
                for precision in runs:
                    runs[precision].append(solve(k, rhs, precision))
            (td, md, _, xd), (tm, mm, its, xm) = (min(r, key=lambda run: run[0]) for r in runs.values())
            gib = 2.0**30
            table.add(checked.name, f"{k.shape[0]:,}", f"{td:.1f}, {md / gib:.2f}", f"{tm:.1f}, {mm / gib:.2f}, {its}",
                      f"{np.abs(xm - xd).max() / np.abs(xd).max():.1e}, {abs(xm[rotation] / xd[rotation] - 1):.1e}")
            print(table.rows[-1], flush=True)
    settings = (f"Study {study.name}, result mesh; fea.linsolve.SPDFactorization with PARDISO, least time of "
                f"{args.repeats} alternated runs in one process; memory: the resident set's largest growth during a "
                "factorization and solve")
    print(f"machine: {machine()}\n{settings}\n{table.markdown()}")
    if args.docs:
        write_fragment("linear_solve_precision", table, settings)


if __name__ == "__main__":
    main()
