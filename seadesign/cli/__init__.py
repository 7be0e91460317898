"""The `seadesign` command: a thin layer that parses options, calls the library and prints.

Each group of subcommands lives in its own module and registers itself on `main`.
"""

from __future__ import annotations

import importlib

import click

from seadesign import __version__
from seadesign.errors import SeadesignError


# Subcommand modules register themselves on `main` when imported; each is imported only when one
# of its commands runs (or for the command list), so `seadesign sweep` does not load torch.
COMMAND_MODULES = {
    "init": "design_cmds", "geometry": "design_cmds", "export": "design_cmds",
    "solve": "fea_cmds", "sweep": "sweep_cmds", "explore": "explore_cmds",
    "data": "data_cmds", "simulate": "data_cmds", "simulate-bench": "data_cmds", "effects": "data_cmds",
    "train": "corrector_cmds", "evaluate": "corrector_cmds", "iterate": "corrector_cmds",
    "explain": "loop_cmds", "explain-thesis": "loop_cmds",
}


class _Group(click.Group):
    """Click group with lazily imported subcommands that turns SeadesignError into a clean
    one-line error (exit code 2)."""

    def list_commands(self, ctx: click.Context) -> list[str]:  # noqa: D102
        return sorted(COMMAND_MODULES)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:  # noqa: D102
        if name not in self.commands and name in COMMAND_MODULES:
            importlib.import_module(f"seadesign.cli.{COMMAND_MODULES[name]}")
        return super().get_command(ctx, name)

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

