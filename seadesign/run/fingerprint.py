"""Fingerprints of the project's own code for cache keys.

A cached result is keyed on the source of the modules that compute it and of every project
module they import, directly or not (imports inside functions included, parent packages too).
The imports are found by reading the source, so nothing is imported to take a fingerprint.
A change to any of those files, even a comment, gives a new key: results are recomputed rather
than ever reused from other code.
"""

from __future__ import annotations

import ast
import functools
import hashlib
from pathlib import Path

PACKAGE = "seadesign"
PACKAGE_DIR = Path(__file__).resolve().parents[1]


def module_path(name: str) -> Path | None:
    """The file of a project module (`seadesign.a.b` -> a/b.py or a/b/__init__.py), None if none."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = PACKAGE_DIR.joinpath(*parts[1:])
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _parents(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def project_imports(name: str, source: bytes) -> set[str]:
    """The project modules that `source` (module `name`) imports, with their parent packages."""
    found: set[str] = set()
    package = name if module_path(name) and module_path(name).name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == PACKAGE)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            if base.split(".")[0] != PACKAGE:
                continue
            found.add(base)
            found.update(f"{base}.{a.name}" for a in node.names if module_path(f"{base}.{a.name}"))
    return {m for name_ in found for m in [name_, *_parents(name_)] if module_path(m)}


@functools.cache
def code_fingerprint(*modules: str) -> str:
    """SHA-256 (32 hex digits) of the source of `modules` and all project modules they import."""
    digests: dict[str, str] = {}
    todo = [m for name in modules for m in [name, *_parents(name)]]
    while todo:
        name = todo.pop()
        if name in digests:
            continue
        path = module_path(name)
        if path is None:
            raise ValueError(f"{name} is not a module of the {PACKAGE} package")
        source = path.read_bytes()
        digests[name] = hashlib.sha256(source).hexdigest()
        todo.extend(project_imports(name, source) - digests.keys())
    text = "\n".join(f"{k} {v}" for k, v in sorted(digests.items()))
    return hashlib.sha256(text.encode()).hexdigest()[:32]
