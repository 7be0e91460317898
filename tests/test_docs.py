"""The documentation: the site builds with warnings as errors, every Python example in it and in the README
runs, and every `seadesign` command line shown names a real command and real options.

A Python example that truly cannot run in a minute (a full sweep, a trained bundle) is marked by the line
`<!-- no-test: reason -->` right above its fence; the reason must say what it needs and how long that takes
at full size.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import require_module

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").rglob("*.md")])
FENCE = re.compile(r"^(?P<indent> *)```(?P<lang>[a-z]*)\n(?P<body>.*?)^(?P=indent)```$", re.MULTILINE | re.DOTALL)
NO_TEST = re.compile(r"<!-- no-test: (?P<reason>[^>]*?) -->\s*$")


def _blocks(lang: str) -> list[tuple[str, str, str | None]]:
    """(id, code, no-test reason) of every fenced block in `lang` in the README and docs/."""
    out = []
    for page in PAGES:
        text = page.read_text()
        for m in FENCE.finditer(text):
            if m.group("lang") != lang:
                continue
            before = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
            skip = NO_TEST.search(before)
            line = text[:m.start()].count("\n") + 1
            body = "\n".join(l[len(m.group("indent")):] for l in m.group("body").splitlines())
            out.append((f"{page.relative_to(ROOT)}:{line}", body, skip.group("reason") if skip else None))
    return out


PYTHON = _blocks("python")
SHELL = _blocks("bash")


def test_there_are_examples():
    assert any(i.startswith("README.md") for i, _, _ in PYTHON), "the README's Python example is gone"
    assert len(PYTHON) >= 3


@pytest.mark.parametrize("block_id,code,reason", PYTHON, ids=[b[0] for b in PYTHON])
def test_python_example_runs(block_id, code, reason, tmp_path, monkeypatch):
    if reason is not None:
        assert re.search(r"\d+ ?(s|min|h)\b", reason), f"{block_id}: a no-test reason must say the full-size time"
        pytest.skip(f"{block_id}: {reason}")
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("SEADESIGN_CACHE", str(tmp_path / "cache"))
    exec(compile(code, block_id, "exec"), {"__name__": "__docs__"})  # noqa: S102 (the docs' own examples)


def _command_lines() -> list[tuple[str, list[str]]]:
    out = []
    for block_id, body, _ in SHELL:
        for line in body.replace("\\\n", " ").splitlines():
            for part in re.split(r"&&|;|\|", line):
                words = shlex.split(part.strip(), comments=True) if part.strip() else []
                if words and words[0] == "seadesign":
                    out.append((block_id, words[1:]))
    return out


COMMANDS = _command_lines()


@pytest.mark.parametrize("block_id,words", COMMANDS, ids=[f"{b}:{' '.join(w[:2])}" for b, w in COMMANDS])
def test_shell_example_names_real_commands_and_options(block_id, words):
    import click

    from seadesign.cli import main

    ctx = click.Context(main)
    command, rest = main, list(words)
    while isinstance(command, click.Group) and rest and not rest[0].startswith("-"):
        sub = command.get_command(ctx, rest[0])
        assert sub is not None, f"{block_id}: `seadesign {' '.join(words)}`: no command {rest[0]!r}"
        command, rest = sub, rest[1:]
    options = {opt for p in command.params for opt in (*p.opts, *p.secondary_opts)} | {"--help", "-h"}
    for word in rest:
        if word.startswith("-"):
            name = word.split("=", 1)[0]
            assert name in options, f"{block_id}: `seadesign {' '.join(words)}`: {command.name} has no option {name}"


def test_site_builds_strict(tmp_path):
    """`mkdocs build --strict`: skipped when the doc tools are not installed, failed under CI=true (CI installs
    them with the `test` extra)."""
    for module in ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_click"):
        require_module(module, "pip install -e '.[docs]'")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
           "NO_MKDOCS_2_WARNING": "1"}
    run = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                         cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert (tmp_path / "site" / "reference" / "cli" / "index.html").read_text().count("seadesign sweep") > 0
    config = (tmp_path / "site" / "reference" / "config" / "index.html").read_text()
    assert "requirements.max_standing_deflection_deg" in config  # the generated table of study keys


def test_every_validation_fragment_is_written_by_a_benchmark_and_shown():
    """The measured tables of the docs come from the benchmark scripts (`--docs`): every fragment a page includes
    is one a script writes, and every fragment a script writes is included by a page."""
    fragments = ROOT / "docs" / "validation" / "_fragments"
    written = set()
    for script in (ROOT / "benchmarks").glob("*.py"):
        text = script.read_text()
        written |= set(re.findall(r'write_fragment\("(\w+)"', text))
        if "TABLES = {" in text:  # validation.py: one fragment per table it measures
            written |= set(re.findall(r'"(\w+)": \w+', text.split("TABLES = {", 1)[1].split("}", 1)[0]))
    included = {m for page in (ROOT / "docs").rglob("*.md")
                for m in re.findall(r'--8<-- "validation/_fragments/(\w+)\.md"', page.read_text())}
    assert included <= written, f"fragments no benchmark writes: {sorted(included - written)}"
    assert written <= included, f"fragments no page shows: {sorted(written - included)}"
    assert {p.stem for p in fragments.glob("*.md")} == included
