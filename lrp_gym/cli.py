"""``lrp-gym`` command line. Subcommands live in :mod:`lrp_gym.commands`, one module each.

Every module there exposes ``register(app)``; this file only assembles them and turns bad input
(typer's own usage errors included) into one ``error: ...`` line with exit code 2 instead of a
traceback or a boxed panel.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys

import typer
from rich.console import Console
from typer.core import TyperCommand

from lrp_gym import __version__, commands
from lrp_gym.commands._common import ScenarioCommand
from lrp_gym.config import ScenarioError
from lrp_gym.errors import InputError

app = typer.Typer(
    name="lrp-gym",
    help=(
        "Radar positioning with passive retroreflectors (LRPs): validate scenarios, run the "
        "FMCW radar chain, track reflectors, design layouts, localise, and drive the robot. "
        "Every command takes --help."
    ),
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    # Plain click help: no <bool> metavars, paragraphs rewrapped to the terminal, and square
    # brackets (units such as [m/s]) are shown instead of being read as markup.
    rich_markup_mode=None,
    context_settings={"max_content_width": 100},
)
err_console = Console(stderr=True)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"lrp-gym {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Radar positioning with passive retroreflectors (LRPs)."""


def _register_all() -> None:
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        module.register(app)
    for command in app.registered_commands:
        # positional SCENARIO with a hidden --scenario alias, on every command that has one
        if command.cls in (None, TyperCommand):
            command.cls = ScenarioCommand


_register_all()


def usage_message(exc: typer.TyperException) -> str:
    """A click usage error as the project's one-line message, naming the option."""
    param = getattr(exc, "param", None)
    hint = getattr(exc, "param_hint", None)
    if param is not None or hint is not None:
        if hint is None:
            opts = getattr(param, "opts", None) or []
            name = getattr(param, "name", None) or ""
            hint = " / ".join(opts) if opts and opts[0].startswith("-") else name.upper()
        if not isinstance(hint, str):
            hint = " / ".join(hint)
        text = f"{hint.replace(chr(39), '')}: {exc.message}"
    else:
        text = exc.format_message()
    text = " ".join(text.split())  # one line
    ctx = getattr(exc, "ctx", None)
    if ctx is not None:
        text += f" (see {ctx.command_path} --help)"
    return text


def _error(message: str) -> None:
    err_console.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    sys.exit(2)


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point."""
    try:
        rv = app(args=argv, prog_name="lrp-gym", standalone_mode=False)
    except ScenarioError as exc:
        src = f" {exc.source}" if exc.source else ""
        err_console.print(f"[bold red]error:[/] invalid scenario{src}", highlight=False)
        for problem in exc.problems:
            err_console.print(f"  - {problem}", highlight=False, markup=False)
        sys.exit(2)
    except InputError as exc:
        _error(str(exc).replace("[", "\\["))
    except typer.TyperException as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            typer.echo(exc.format_message())  # bare `lrp-gym`: the help, as before
            sys.exit(2)
        _error(usage_message(exc).replace("[", "\\["))
    except (KeyboardInterrupt, typer.Abort):
        err_console.print("interrupted")
        sys.exit(130)
    sys.exit(rv if isinstance(rv, int) else 0)


if __name__ == "__main__":
    main()
