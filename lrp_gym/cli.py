"""``lrp-gym`` command line. Subcommands live in :mod:`lrp_gym.commands`, one module each.

Every module there exposes ``register(app)``; this file only assembles them and turns bad input
into a clear message with exit code 2 instead of a traceback.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import typer
from rich.console import Console

from lrp_gym import commands
from lrp_gym.config import ScenarioError
from lrp_gym.errors import InputError

app = typer.Typer(
    name="lrp-gym",
    help=(
        "Radar positioning with passive retroreflectors (LRPs): validate scenarios, run the "
        "FMCW radar chain, track reflectors, design layouts, localise, and drive the robot."
    ),
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    rich_markup_mode="rich",
)
err_console = Console(stderr=True)


@app.callback()
def _root() -> None:
    """Radar positioning with passive retroreflectors (LRPs)."""


def _register_all() -> None:
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        module.register(app)


_register_all()


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    try:
        app(args=argv, prog_name="lrp-gym")
    except ScenarioError as exc:
        src = f" {exc.source}" if exc.source else ""
        err_console.print(f"[bold red]error:[/] invalid scenario{src}", highlight=False)
        for problem in exc.problems:
            err_console.print(f"  - {problem}", highlight=False, markup=False)
        sys.exit(2)
    except InputError as exc:
        err_console.print(f"[bold red]error:[/] {exc}", highlight=False)
        sys.exit(2)
    except KeyboardInterrupt:
        err_console.print("interrupted")
        sys.exit(130)


if __name__ == "__main__":
    main()
