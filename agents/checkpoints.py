"""What keeps a training run safe: checkpoints, the best model, a clean stop, worker shutdown.

* :class:`RunCallback` writes a checkpoint (model zip + statistics JSON, see
  :mod:`agents.model_io`) every ``checkpoint_freq`` total env steps and ends ``learn`` at the
  next step once a stop was requested.
* :class:`StopSignals` is the one handler for SIGINT and SIGTERM: the first signal asks the run
  to stop after the current step (it then saves a checkpoint), a second one stops at once.
* :func:`close_venv` shuts subprocess workers down with a timeout and then terminates them, so
  a stopped run never waits forever on a worker.
"""

from __future__ import annotations

import re
import signal
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, EvalCallback

from agents.model_io import save_model

_CKPT = re.compile(r"rl_model_(\d+)_steps\.zip$")


def list_checkpoints(run_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of every checkpoint in ``run_dir/checkpoints``, newest first."""
    found = []
    for p in (Path(run_dir) / "checkpoints").glob("rl_model_*_steps.zip"):
        m = _CKPT.search(p.name)
        if m:
            found.append((int(m.group(1)), p))
    return sorted(found, reverse=True)


def checkpoint_path(run_dir: Path, steps: int) -> Path:
    """``checkpoints/rl_model_<steps>_steps.zip`` (SB3's CheckpointCallback naming)."""
    return run_dir / "checkpoints" / f"rl_model_{steps}_steps.zip"


class StopSignals:
    """One handler for SIGINT and SIGTERM while training (a context manager).

    The first signal sets :attr:`requested` (the run stops after the current step and saves a
    checkpoint); another one raises KeyboardInterrupt to stop at once.
    """

    def __init__(self, log: Callable[[str], None]) -> None:
        self.requested: str | None = None
        self._log = log
        self._previous: dict[int, Any] = {}

    def _handle(self, signum: int, frame: Any) -> None:
        if self.requested is not None:
            raise KeyboardInterrupt
        self.requested = signal.Signals(signum).name
        self._log(
            f"{self.requested}: stopping after the current step and saving a checkpoint "
            "(signal again to stop at once)"
        )

    def __enter__(self) -> StopSignals:
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self._previous[sig] = signal.signal(sig, self._handle)
            except ValueError:  # not the main thread: leave signals alone
                break
        return self

    def __exit__(self, *exc: Any) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def ignore_stop_signals(env: Any) -> Any:
    """Env wrapper hook run in each worker: only the main process reacts to Ctrl-C / SIGTERM.

    A terminal's Ctrl-C reaches the whole process group; workers that died of it would leave the
    main process waiting for their answer. The main process shuts them down instead.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    return env


def close_venv(venv: Any, timeout: float = 5.0) -> None:
    """Close a (wrapped) VecEnv; subprocess workers get ``timeout`` s, then are terminated.

    SB3's ``SubprocVecEnv.close`` first waits for pending step results and then joins without
    a timeout, which hangs if the run was interrupted mid-step or a worker died.
    """
    from stable_baselines3.common.vec_env import SubprocVecEnv

    base = venv
    while hasattr(base, "venv"):
        base = base.venv
    if not isinstance(base, SubprocVecEnv):
        base.close()
        return
    if base.closed:
        return
    base.closed = True
    for remote in base.remotes:
        try:
            remote.send(("close", None))
        except OSError:  # the worker is gone already
            pass
    deadline = time.monotonic() + timeout
    for process in base.processes:
        process.join(max(deadline - time.monotonic(), 0.0))
    for process in base.processes:
        if process.is_alive():
            process.terminate()
            process.join(1.0)
        if process.is_alive():
            process.kill()
            process.join(1.0)
    for remote in base.remotes:
        remote.close()


class RunCallback(BaseCallback):
    """Periodic checkpoints (every ``every`` total env steps) and the graceful stop.

    Parameters
    ----------
    run_dir : Path
        Checkpoints go to ``run_dir/checkpoints``.
    every : int
        Checkpoint interval in total env steps (over all envs); aligned to multiples of it,
        so a resumed run keeps the same schedule.
    stop : StopSignals, optional
        ``learn`` ends at the next step once ``stop.requested`` is set.
    """

    def __init__(self, run_dir: Path, every: int, stop: StopSignals | None = None) -> None:
        super().__init__()
        self.run_dir, self.every, self.stop = run_dir, max(int(every), 1), stop
        self.saved: list[Path] = []

    def _on_step(self) -> bool:
        n = self.model.num_timesteps
        n_envs = self.model.n_envs
        if n // self.every > (n - n_envs) // self.every:
            self.saved = save_model(self.model, checkpoint_path(self.run_dir, n))
        return not (self.stop is not None and self.stop.requested)


class SaveBestCallback(BaseCallback):
    """EvalCallback's ``callback_on_new_best``: save the new best model with its statistics."""

    def __init__(self, best_dir: Path) -> None:
        super().__init__()
        self.best_dir = best_dir

    def _on_step(self) -> bool:
        save_model(self.model, self.best_dir / "best_model.zip")
        return True


class ProgressCallback(BaseCallback):
    """A progress bar over the whole run: from the resumed count to the (rounded) target."""

    def __init__(self, start: int, target: int) -> None:
        super().__init__()
        self.start, self.target = start, target
        self.bar: Any = None

    def _on_training_start(self) -> None:
        from tqdm import TqdmExperimentalWarning
        from tqdm.rich import tqdm

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", category=TqdmExperimentalWarning)
            self.bar = tqdm(total=self.target, initial=self.start, unit="steps")

    def _on_step(self) -> bool:
        self.bar.update(self.training_env.num_envs)
        return True

    def _on_training_end(self) -> None:
        self.bar.refresh()
        self.bar.close()


def make_evaluation(
    run_dir: Path, eval_env: Any, eval_freq: int, n_eval: int, n_envs: int, start: int
) -> EvalCallback:
    """EvalCallback writing ``eval/evaluations.npz`` and ``best/`` (model + statistics JSON).

    On resume the learning curve so far is restored and the call counter set so evaluations
    keep falling on multiples of ``eval_freq`` total steps.
    """
    evaluation = EvalCallback(
        eval_env,
        callback_on_new_best=SaveBestCallback(run_dir / "best"),
        n_eval_episodes=n_eval,
        eval_freq=max(eval_freq // n_envs, 1),
        log_path=str(run_dir / "eval"),
        best_model_save_path=None,  # SaveBestCallback writes it atomically with its statistics
        deterministic=True,
        verbose=0,
    )
    evaluation.n_calls = start // n_envs
    _restore_curve(evaluation, run_dir, start)
    return evaluation


def _restore_curve(evaluation: EvalCallback, run_dir: Path, start: int) -> None:
    """Continue the learning curve of an earlier run (points up to ``start`` steps)."""
    npz = run_dir / "eval" / "evaluations.npz"
    if start == 0 or not npz.is_file():
        return
    with np.load(npz) as d:
        keep = d["timesteps"] <= start
        evaluation.evaluations_timesteps = [int(t) for t in d["timesteps"][keep]]
        evaluation.evaluations_results = [list(r) for r in d["results"][keep]]
        evaluation.evaluations_length = [list(r) for r in d["ep_lengths"][keep]]
        if "successes" in d and len(d["successes"]) == len(keep):
            evaluation.evaluations_successes = [list(r) for r in d["successes"][keep]]
    if evaluation.evaluations_results:
        means = [float(np.mean(r)) for r in evaluation.evaluations_results]
        evaluation.best_mean_reward = max(means)


def evaluate_now(evaluation: EvalCallback, model: Any) -> None:
    """Evaluate at the current step unless that was just done (runs shorter than eval_freq)."""
    done = evaluation.evaluations_timesteps
    if done and done[-1] == model.num_timesteps:
        return
    freq = evaluation.eval_freq
    evaluation.num_timesteps, evaluation.eval_freq = model.num_timesteps, 1
    try:
        evaluation._on_step()
    finally:
        evaluation.eval_freq = freq


def last_eval(evaluation: EvalCallback) -> dict[str, Any] | None:
    """The newest point of the learning curve (None before the first evaluation)."""
    if not evaluation.evaluations_timesteps:
        return None
    res = np.asarray(evaluation.evaluations_results[-1], dtype=float)
    out = {
        "timesteps": int(evaluation.evaluations_timesteps[-1]),
        "mean_reward": float(res.mean()),
        "mean_ep_length": float(np.mean(evaluation.evaluations_length[-1])),
    }
    if evaluation.evaluations_successes:
        out["success_rate"] = float(np.mean(evaluation.evaluations_successes[-1]))
    return out
