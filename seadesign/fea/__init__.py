"""Linear elasticity of the compliant element: P2 tetrahedra, rigid couplings, one factorization
for both load cases, stress recovery, and CalculiX as an independent check.

Entry points: solve_load_cases() (plain numbers), analyse() (numbers + fields for export).
"""

from seadesign.fea.loadcases import Analysis, analyse, solve_load_cases

__all__ = ["Analysis", "analyse", "solve_load_cases"]
