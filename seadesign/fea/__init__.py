"""Linear elasticity of the compliant element: P2 tetrahedra, rigid couplings, one factorization
for both load cases, stress recovery, and CalculiX as an independent check.

Entry point: analyse() (typed load-case results in .results, see results.py, plus the fields for export).
"""

from seadesign.fea.loadcases import Analysis, analyse

__all__ = ["Analysis", "analyse"]
