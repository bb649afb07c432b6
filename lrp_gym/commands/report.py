"""``lrp-gym report``: rerun the README's result rows and rewrite its results table."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import typer

from lrp_gym.commands import _results as res
from lrp_gym.commands._common import choice, console, err_console, write_json, write_text, wrote
from lrp_gym.errors import InputError


def report(
    rerun: bool = typer.Option(
        False, "--rerun", help="Rerun the rows' commands and store their JSON in docs/results."
    ),
    only: str = typer.Option(
        None, "--only", metavar="KEY,...", help="With --rerun: only these rows (by commas)."
    ),
    check: bool = typer.Option(
        False, "--check", help="Only check that README.md matches docs/results (no writes)."
    ),
) -> None:
    """Rewrite the results table in README.md from docs/results/*.json.

    Each row's numbers and its "missed" mark come from the JSON its command printed; rows
    without a stored JSON keep their typed text, marked "(not regenerated)".
    """
    runnable = [r.key for r in res.ROWS if r.commands]
    keys = runnable
    if only is not None:
        keys = [k.strip() for k in only.split(",") if k.strip()]
        for k in keys:
            choice(k, runnable, "--only")
        if not rerun:
            raise InputError("--only: only used with --rerun")
    if check and rerun:
        raise InputError("--check: does not rerun; drop --rerun")
    if rerun:
        for row in res.ROWS:
            if row.key in keys:
                _rerun(row)
    readme = res.README.read_text(encoding="utf-8")
    new = res.replace_table(readme, res.render_table(res.load_results()))
    if check:
        if new != readme:
            raise InputError("README.md: the results table is out of date; run lrp-gym report")
        console.print("README.md results table matches docs/results")
        return
    if new != readme:
        write_text(new, res.README)
        wrote(res.README)
    else:
        console.print("README.md results table is up to date")


def _rerun(row: res.Row) -> None:
    start = time.perf_counter()
    commands, results = [], []
    for args in row.commands:
        argv = [*args, "--json"]
        commands.append("lrp-gym " + " ".join(argv))
        err_console.print(f"running {commands[-1]}", highlight=False, markup=False, soft_wrap=True)
        proc = subprocess.run(
            [sys.executable, "-m", "lrp_gym.cli", *argv],
            capture_output=True,
            text=True,
            check=False,
        )
        if proc.returncode != 0:
            raise InputError(f"{row.key}: {commands[-1]} failed: {proc.stderr.strip()[-300:]}")
        results.append(json.loads(proc.stdout))
    several = row.argv is None  # a row of several runs stores the list of their results
    doc = {
        "command": commands if several else commands[0],
        "elapsed_s": round(time.perf_counter() - start, 1),
        "result": results if several else results[0],
    }
    wrote(write_json(doc, res.RESULTS_DIR / f"{row.key}.json"))


def register(app: typer.Typer) -> None:
    app.command("report", short_help="Rerun the README's result rows; rewrite its table.")(report)
