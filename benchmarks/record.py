"""What every benchmark prints and writes: the machine it ran on, and its table as a page fragment of the
documentation (`--docs`), with the command, the settings, the machine, the date and the commit. The site
includes the fragments as they were last written; building it never reruns a benchmark."""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FRAGMENTS = ROOT / "docs" / "validation" / "_fragments"


def cpu_model() -> str:
    """The CPU's model name (Linux), else the platform's processor string."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> str:
    """One line: CPU, cores, load average now, Python and NumPy versions."""
    import numpy as np

    load = os.getloadavg()
    return (f"{cpu_model()}, {os.cpu_count()} cores, load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}, "
            f"Python {platform.python_version()}, NumPy {np.__version__}")


def commit() -> str:
    """The checkout's short commit, "+ changes" when the tree differs from it (the fragments aside: a run that
    writes several changes them itself)."""
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()

    head = git("rev-parse", "--short", "HEAD") or "unknown"
    changed = git("status", "--porcelain", "--untracked-files=no", "--", ".", ":!docs/validation/_fragments")
    return head + (" + changes" if changed else "")


def add_docs_option(parser: argparse.ArgumentParser, *fragments: str) -> None:
    """`--docs`: write the run's table(s) into docs/validation/_fragments/<fragment>.md."""
    parser.add_argument("--docs", action="store_true",
                        help="write the table into the documentation: " + ", ".join(
                            f"docs/validation/_fragments/{f}.md" for f in fragments))


@dataclass
class Table:
    """A Markdown table: a header with units and rows of formatted cells."""

    columns: list[str]
    rows: list[list[str]] = field(default_factory=list)

    def add(self, *cells: object) -> None:
        if len(cells) != len(self.columns):
            raise ValueError(f"a row of {len(cells)} cells for {len(self.columns)} columns")
        self.rows.append([str(c) for c in cells])

    def markdown(self) -> str:
        lines = ["| " + " | ".join(self.columns) + " |", "|" + "---|" * len(self.columns)]
        return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in self.rows])


def command() -> str:
    """The command line that ran this benchmark, from the repository root."""
    script = Path(sys.argv[0]).resolve()
    shown = script.relative_to(ROOT) if script.is_relative_to(ROOT) else script
    return " ".join(["python", str(shown), *sys.argv[1:]])


def write_fragment(name: str, table: Table, settings: str, note: str = "") -> Path:
    """Write docs/validation/_fragments/<name>.md: a caption (command, settings, machine, date, commit, note)
    and the table. Returns the path written."""
    FRAGMENTS.mkdir(parents=True, exist_ok=True)
    caption = (f"*Command: `{command()}`. {settings.rstrip('.')}. Machine: {machine()}. "
               f"Run on {datetime.date.today().isoformat()}, commit {commit()}." + (f" {note}" if note else "") + "*")
    path = FRAGMENTS / f"{name}.md"
    path.write_text(caption + "\n\n" + table.markdown() + "\n")
    print(f"wrote {path.relative_to(ROOT)}")
    return path
