"""The API's docstrings: every entry point of ``import seadesign as sd`` carries numpydoc sections (Parameters naming
each argument, Returns, Raises, Examples), the public methods of its classes too, and the examples with a printed
answer give that answer (doctest)."""

from __future__ import annotations

import doctest
import inspect
import re

import pytest

import seadesign as sd

SECTION = re.compile(r"^(\w[\w ]*)\n-{3,}$", re.MULTILINE)


def sections(doc: str) -> dict[str, str]:
    """numpydoc section title -> its body."""
    heads = list(SECTION.finditer(doc))
    return {h.group(1): doc[h.end():heads[i + 1].start() if i + 1 < len(heads) else len(doc)]
            for i, h in enumerate(heads)}


def documented_parameters(body: str) -> set[str]:
    """The names a Parameters section documents (``name : type`` lines, ``a, b : type`` for several)."""
    names = set()
    for line in body.splitlines():
        head = re.match(r"^([*\w][\w*, ]*?)\s:", line)
        if head:
            names |= {n.strip().lstrip("*") for n in head.group(1).split(",")}
    return names


def signature_parameters(function) -> set[str]:
    return {p.name for p in inspect.signature(function).parameters.values() if p.name not in ("self", "cls")}


def entry_points():
    return [(name, getattr(sd, name)) for name in sd.__all__ if name != "__version__"]


def public_methods():
    for name, obj in entry_points():
        if not inspect.isclass(obj) or issubclass(obj, Exception):
            continue
        for attribute, member in vars(obj).items():
            if attribute.startswith("_"):
                continue
            if isinstance(member, (staticmethod, classmethod)):
                member = member.__func__
            if inspect.isfunction(member) or isinstance(member, property):
                yield f"{name}.{attribute}", member


@pytest.mark.parametrize("name, function", [(n, f) for n, f in entry_points() if not inspect.isclass(f)])
def test_entry_points_have_numpydoc_sections(name, function):
    doc = inspect.getdoc(function) or ""
    found = sections(doc)
    missing = [s for s in ("Parameters", "Returns", "Raises", "Examples") if s not in found]
    assert not missing, f"sd.{name}: no {missing} section"
    assert signature_parameters(function) <= documented_parameters(found["Parameters"]), (
        f"sd.{name}: Parameters misses {sorted(signature_parameters(function) - documented_parameters(found['Parameters']))}")
    assert ">>>" in found["Examples"]


@pytest.mark.parametrize("name, member", list(public_methods()))
def test_public_methods_have_numpydoc_sections(name, member):
    doc = inspect.getdoc(member.fget if isinstance(member, property) else member) or ""
    assert doc, f"{name} has no docstring"
    if isinstance(member, property):
        return
    found = sections(doc)
    parameters = signature_parameters(member)
    missing = [s for s in ("Returns", "Examples") + (("Parameters",) if parameters else ()) if s not in found]
    assert not missing, f"{name}: no {missing} section"
    if parameters:
        assert parameters <= documented_parameters(found["Parameters"]), f"{name}: Parameters misses an argument"


def test_the_parser_finds_what_is_missing():
    """The section parser itself: a docstring without Raises, or with an argument undocumented, is caught."""
    def f(a, b_mm):
        """Do.

        Parameters
        ----------
        a : float
            A (N).

        Returns
        -------
        float
        """
    found = sections(inspect.getdoc(f))
    assert set(found) == {"Parameters", "Returns"}
    assert documented_parameters(found["Parameters"]) == {"a"} != signature_parameters(f)


@pytest.mark.parametrize("name", ["Study", "Material", "Candidate"])
def test_printed_answers_of_the_examples_hold(name):
    """The examples of the design objects that print an answer give it (run as doctests on the shipped study)."""
    finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    tests = [t for t in finder.find(getattr(sd, name), name) if t.examples]
    assert tests
    for test in tests:
        runner.run(test)
    assert runner.summarize(verbose=False).failed == 0
