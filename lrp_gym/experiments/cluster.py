"""Independent units of work as Ray tasks, results in unit order, partial results on disk.

A study (a robustness matrix, an evaluation, a layout search) is cut into units whose results do
not depend on each other or on the order they finish in: each unit seeds itself from its own
identifiers (a cell's episode seeds, a slice of candidates drawn up front). :func:`run_units`
sends them to Ray, appends each result to a JSON-lines *sidecar* as it arrives, and returns
the results in unit order, so the caller reassembles exactly what the one-process run computes.
A sidecar left by an interrupted study is read back with ``resume=True``: its units are not run
again.

Ray is imported only here and only when a study asks for it (``pip install lrp-gym[cluster]``).
"""

from __future__ import annotations

import json
import os
import socket
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import lrp_gym

#: The hint every "Ray is missing" message gives.
INSTALL_HINT = "pip install lrp-gym[cluster]"
#: Seconds to wait for a cluster's address to answer before giving up.
PROBE_TIMEOUT_S = 5.0
#: The address that starts a Ray on this machine (Ray's own name for it).
LOCAL = "local"
#: Object store of a Ray started here: small, the units return a few MB at most.
LOCAL_OBJECT_STORE_BYTES = 200_000_000
SIDECAR_SUFFIX = ".partial.jsonl"
_FORMAT = "lrp-gym partial results 1"


def import_ray() -> Any:
    """The ``ray`` module, or a ValueError naming ``ray`` and the extra to install."""
    try:
        import ray
    except ImportError:
        raise ValueError(f"ray: Ray is not installed; {INSTALL_HINT}") from None
    return ray


def check_address(address: str) -> str:
    """``local``, ``auto``, ``HOST:PORT`` or ``ray://HOST:PORT`` (ValueError naming ``address``).

    A bare word is rejected rather than taken as a host name: ``--ray ipin2023`` most likely
    meant the scenario, which goes before ``--ray``.
    """
    text = address.strip()
    if text in (LOCAL, "auto") or (":" in text and not text.startswith(":")):
        return text
    raise ValueError(
        f"address: expected local, auto or HOST:PORT, got {address!r} (a SCENARIO goes "
        "before the option, or write --ray=ADDRESS)"
    )


def probe(address: str, timeout_s: float = PROBE_TIMEOUT_S) -> None:
    """Fail fast when nothing listens at ``HOST:PORT`` (``ray://`` included): ``ray.init``
    retries an unreachable cluster for minutes. ValueError naming ``address``."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s).close()
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ValueError(f"address: no Ray cluster answers at {address!r} ({reason})") from None


def project_root() -> Path:
    """The folder that holds the ``lrp_gym`` package (a checkout's root, or site-packages)."""
    return Path(lrp_gym.__file__).resolve().parent.parent


def connect(address: str, num_cpus: int | None = None) -> Any:
    """Start (``local``) or join (``auto``, ``HOST:PORT``) Ray unless this process already is.

    A local Ray gets this machine's cores (or ``num_cpus``), no dashboard, a small object
    store and workers at normal priority (``RAY_worker_niceness=0`` unless set). Workers import this checkout: its root goes first on their ``PYTHONPATH``, so a run
    from a source tree does not pick up another installed copy. ValueError naming ``address``
    when there is no cluster there.
    """
    ray = import_ray()
    if ray.is_initialized():
        return ray
    if address not in (LOCAL, "auto"):
        probe(address)
    path = os.pathsep.join(p for p in (str(project_root()), os.environ.get("PYTHONPATH")) if p)
    kwargs: dict[str, Any] = {
        "runtime_env": {"env_vars": {"PYTHONPATH": path}},
        "include_dashboard": False,
        "log_to_driver": False,
        "logging_level": "warning",
    }
    if address == LOCAL:
        # Ray nices its workers (15) below the driver; here the driver only waits, and on a
        # shared machine niced workers lose every core to other users' processes.
        os.environ.setdefault("RAY_worker_niceness", "0")
        kwargs |= {
            "num_cpus": num_cpus or os.cpu_count() or 1,
            "object_store_memory": LOCAL_OBJECT_STORE_BYTES,
        }
    try:
        ray.init(address=address, **kwargs)
    except ConnectionError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ValueError(f"address: no Ray cluster at {address!r} ({first})") from None
    return ray


def sidecar_path(out: Path) -> Path:
    """Where the partial results of a study written to ``out`` go: beside it."""
    return out.with_name(out.name + SIDECAR_SUFFIX)


class Sidecar:
    """The JSON-lines file of finished units: a header line (the study), then one line per unit.

    Parameters
    ----------
    path : Path
    study : dict
        What identifies the study (command, scenario, seeds, ...): a resumed sidecar must have
        been written for the same one.
    """

    def __init__(self, path: Path, study: dict[str, Any]) -> None:
        self.path = Path(path)
        self.study = json.loads(json.dumps(study, default=str))  # as it reads back

    def load(self) -> dict[str, Any]:
        """The finished units (key -> encoded result); ValueError naming ``resume`` if the file
        belongs to another study. A last line cut short by an interruption is ignored."""
        if not self.path.is_file():
            return {}
        lines = self.path.read_text(encoding="utf-8").splitlines()
        try:
            head = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            head = {}
        if head.get("format") != _FORMAT or head.get("study") != self.study:
            raise ValueError(
                f"resume: {self.path} holds the partial results of another study; remove it "
                "or run the same command"
            )
        done: dict[str, Any] = {}
        for line in lines[1:]:
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue  # cut short when the study was killed
            done[row["unit"]] = row["result"]
        return done

    def start(self) -> None:
        """Begin a new file with the header (replacing an old one)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("w", encoding="utf-8") as f:
            f.write(json.dumps({"format": _FORMAT, "study": self.study}) + "\n")

    def append(self, key: str, result: Any) -> None:
        """One finished unit, flushed to disk at once."""
        with self.path.open("a", encoding="utf-8") as f:
            f.write(json.dumps({"unit": key, "result": result}) + "\n")
            f.flush()
            os.fsync(f.fileno())

    def remove(self) -> None:
        """Delete the file (the study is complete and its result written)."""
        self.path.unlink(missing_ok=True)


def run_units(
    task: Callable[[Any], Any],
    units: Sequence[tuple[str, Any]],
    address: str | None = LOCAL,
    sidecar: Sidecar | None = None,
    resume: bool = False,
    encode: Callable[[Any], Any] = lambda r: r,
    decode: Callable[[Any], Any] = lambda r: r,
    on_result: Callable[[str, Any], None] | None = None,
) -> list[Any]:
    """``[task(u) for _, u in units]``, the units run as Ray tasks (one CPU each).

    Parameters
    ----------
    task : callable
        A module-level function of one unit (Ray pickles it and the unit to the workers).
    units : sequence of (key, unit)
        Unique keys name the units in the sidecar.
    address : str or None
        ``local``, ``auto`` or ``HOST:PORT`` (see :func:`connect`); None runs the units here,
        one after another (same results; the reference for tests).
    sidecar : Sidecar, optional
        Every finished unit is appended to it (``encode``-d); without ``resume`` it starts anew.
    resume : bool
        Take the units the sidecar already holds (``decode``-d) instead of running them.
    on_result : callable, optional
        Called with ``(key, result)`` as each unit finishes, read-back ones first.

    Returns
    -------
    list
        The results in the order of ``units``, whatever order the tasks finished in.
    """
    keys = [k for k, _ in units]
    if len(set(keys)) != len(keys):
        raise ValueError("units: keys must be unique")
    done: dict[str, Any] = {}
    if sidecar is not None and resume:
        done = {k: decode(v) for k, v in sidecar.load().items() if k in set(keys)}
    if sidecar is not None and not (resume and sidecar.path.is_file()):
        sidecar.start()

    def finish(key: str, result: Any) -> None:
        done[key] = result
        if sidecar is not None:
            sidecar.append(key, encode(result))
        if on_result is not None:
            on_result(key, result)

    for key in keys:
        if key in done and on_result is not None:
            on_result(key, done[key])
    todo = [(k, u) for k, u in units if k not in done]
    if address is None:
        for key, unit in todo:
            finish(key, task(unit))
    elif todo:
        _run_on_ray(task, todo, check_address(address), finish)
    return [done[k] for k in keys]


def _run_on_ray(
    task: Callable[[Any], Any],
    todo: Sequence[tuple[str, Any]],
    address: str,
    finish: Callable[[str, Any], None],
) -> None:
    """Submit every unit, then hand results over as they arrive (cancel the rest on error)."""
    ray = connect(address)
    remote = ray.remote(num_cpus=1, max_retries=2)(task)
    pending = {remote.remote(unit): key for key, unit in todo}
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                finish(pending.pop(ref), ray.get(ref))
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
