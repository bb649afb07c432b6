"""``--ray [ADDRESS]`` and ``--resume``: the options of the commands whose work runs on Ray.

:mod:`lrp_gym.experiments.cluster` does the work; this module checks the options before any
work starts (Ray installed, the address well formed, the partial results beside ``--out`` of
this study) and makes the sidecar. Nothing here imports Ray until ``--ray`` is given.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from lrp_gym.commands._common import as_flags
from lrp_gym.errors import InputError

#: The value of a bare ``--ray`` (no address): start Ray on this machine.
RAY_LOCAL = "local"


def ray_option(units: str) -> Any:
    """``--ray [ADDRESS]``: an option whose value may be left out (see ``OPTIONAL_VALUES``)."""
    return typer.Option(
        None,
        "--ray",
        metavar="[ADDRESS]",
        help=f"Run {units} as Ray tasks (pip install lrp-gym[cluster]): alone, on a Ray "
        "started here with this machine's cores; auto or HOST:PORT joins a running cluster. "
        "Same numbers as without. With --out, finished tasks are kept beside it in "
        "FILE.partial.jsonl until the result is written.",
    )


def resume_option() -> Any:
    """``--resume``: complete an interrupted ``--ray`` study from its partial results."""
    return typer.Option(
        False,
        "--resume",
        help="With --ray and --out: take the tasks an interrupted run finished "
        "(FILE.partial.jsonl beside --out) and run only the rest.",
    )


def check_ray_options(
    ray: str | None, resume: bool, out_path: Path | None, force: bool, study: dict[str, Any]
) -> Any:
    """Check ``--ray`` and ``--resume`` before any work; the sidecar to write (or None).

    Ray is started or joined here, last, so that an unreachable cluster is reported before
    any work.

    Raises
    ------
    InputError
        Ray not installed (naming ``pip install lrp-gym[cluster]``), a malformed or
        unreachable address,
        ``--resume`` without ``--ray`` / ``--out`` or with another study's partial results,
        or partial results beside ``--out`` that neither ``--resume`` nor ``--force`` allows
        to touch.
    """
    if ray is None:
        if resume:
            raise InputError("--resume: only with --ray (partial results come from Ray tasks)")
        return None
    from lrp_gym.experiments import cluster

    with as_flags(address="--ray", ray="--ray"):
        cluster.check_address(ray)
        cluster.import_ray()
    side = None
    if out_path is not None:
        side = cluster.Sidecar(cluster.sidecar_path(out_path), study)
        if resume:
            with as_flags(resume="--resume"):
                side.load()
        elif side.path.exists() and not force:
            raise InputError(
                f"--out: {side.path} holds the partial results of an earlier run; add "
                "--resume to complete it, or --force to start over"
            )
    elif resume:
        raise InputError("--resume: needs --out (the partial results are kept beside it)")
    with as_flags(address="--ray"):
        cluster.connect(ray)  # before any work: an unreachable cluster fails here
    return side


def reject_random_agent(agent: str, ray: str | None) -> None:
    """The random agent's one generator runs across all episodes: they are not independent
    units, so its numbers would change on Ray."""
    if ray is not None and agent == "random":
        raise InputError(
            "--ray: the random agent draws one action stream across all episodes, which are "
            "then not independent tasks; run it without --ray"
        )


class PolicyFactory:
    """``agents.registry.make_agent(agent, env, model, seed, options)`` as a picklable callable
    of the env: Ray sends it to the workers, which build the policy there."""

    def __init__(
        self, agent: str, model: Path | None, seed: int, options: dict[str, Any] | None = None
    ) -> None:
        # absolute: a worker's folder (or node) is not the driver's
        self.agent, self.seed, self.options = agent, seed, dict(options or {})
        self.model = None if model is None else Path(model).resolve()

    def __call__(self, env: Any) -> Any:
        from agents.registry import make_agent

        return make_agent(self.agent, env, self.model, self.seed, self.options)
