"""The `seadesign` command: a thin layer that parses options, calls the library and prints.

Each group of subcommands lives in its own module and registers itself on `main`.
"""

from __future__ import annotations

import click

from seadesign import __version__
from seadesign.errors import SeadesignError


class _Group(click.Group):
    """Click group that turns SeadesignError into a clean one-line error (exit code 2)."""

    def invoke(self, ctx: click.Context):  # noqa: D102
        try:
            return super().invoke(ctx)
        except SeadesignError as exc:
            raise click.UsageError(str(exc)) from None


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="seadesign")
def main() -> None:
    """Design, verify and calibrate the 3D-printed torsion spring of a series elastic actuator.

    Lengths on the command line are in mm where the option says so (e.g. --thickness-mm);
    everything else is SI (N, m, Pa, Nm, rad).
    """


# Subcommand modules register themselves on `main` when imported.
from seadesign.cli import design_cmds  # noqa: E402,F401
from seadesign.cli import corrector_cmds  # noqa: E402,F401
from seadesign.cli import data_cmds  # noqa: E402,F401
from seadesign.cli import sweep_cmds  # noqa: E402,F401
from seadesign.cli import loop_cmds  # noqa: E402,F401
from seadesign.cli import fea_cmds  # noqa: E402,F401
