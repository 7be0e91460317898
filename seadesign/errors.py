"""Errors that carry a message meant for the user (the CLI prints them without a traceback)."""


class SeadesignError(Exception):
    """Base class: the message names the file/field and says how to fix it."""


class ConfigError(SeadesignError):
    """A study or material file is invalid."""


class SpringFileError(SeadesignError):
    """A spring.json handoff file is missing, unreadable or fails its schema."""


class DataError(SeadesignError):
    """A recording or bench file is malformed."""


class MeshError(SeadesignError):
    """Meshing failed or produced a mesh that cannot be used (named setting and fix in the message)."""


class SolverError(SeadesignError):
    """A finite-element solve failed or its inputs are invalid."""


class NotPositiveDefinite(SolverError):
    """A stiffness matrix has a zero or negative pivot: the structure is under-constrained, or (a
    tangent stiffness on a load path) it has lost stability."""
