"""``lrp-gym evaluate --random-rooms``: the agent on generated rooms, a table row per room and
the numbers pooled over every episode (``lrp_gym.experiments.room_episodes``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from lrp_gym.commands._cluster import PolicyFactory
from lrp_gym.commands._common import (
    as_flags,
    console,
    err_console,
    print_json,
    save_figure,
    table,
    write_json,
    wrote,
)


def random_rooms(
    n: int,
    make_policy: PolicyFactory,
    job: dict[str, Any],
    head: dict[str, Any],
    paths: tuple[Path | None, Path | None],
    json_out: bool,
) -> None:
    """``--random-rooms``: ``job`` (``run_rooms``'s keywords) on rooms 0..n-1, a line per room
    on stderr as it finishes, then the per-room table and the pooled numbers (``--json``: the
    document ``head`` + the summary on stdout); ``paths``: ``--out`` and ``--plot``."""
    from lrp_gym.experiments import room_episodes as rooms

    flags = dict(model_path="--model", agent="--agent", env_id="--env", num_envs="--num-envs")
    with as_flags(**flags):
        results = rooms.run_rooms(range(n), make_policy, progress=_show_room, **job)
    data = rooms.summary(results)
    doc = head | dict(env_id=results[0].env_id, task=results[0].task, fidelity=results[0].fidelity)
    doc |= dict(seed=job["seed"], episodes_per_room=job["episodes"]) | data
    title = (
        f"{doc['agent']} on {n} generated rooms ({doc['task']}, {doc['fidelity']}), "
        f"seeds {job['seed']}..{job['seed'] + job['episodes'] - 1} in each"
    )
    out_path, plot_path = paths
    if out_path is not None:
        write_json(doc, out_path)
    if json_out:
        print_json(doc)
    else:
        _print_rooms(data, title)
    if plot_path is not None:
        from lrp_gym.localization.plotting import plot_reliability

        fig = plot_reliability(
            data["pooled"]["reliability"], title=f"Confidence reliability: {title}"
        )
        save_figure(fig, plot_path)
    for p in paths:
        if p is not None:
            wrote(p, quiet=json_out)


def _pct(share: float | None, unit: str = " %") -> str:
    return "-" if share is None else f"{100 * share:.1f}{unit}"


def _show_room(room: Any) -> None:
    """One line on stderr as a generated room finishes."""
    from lrp_gym.experiments.room_episodes import room_row

    r = room_row(room)
    err_console.print(
        f"room {r['seed']}: {r['size_m'][0]:.1f} x {r['size_m'][1]:.1f} m, {r['obstacles']} "
        f"obstacles, {r['reflectors']} reflectors ({r['kinds']}), {r['episodes']} episodes: "
        f"success {_pct(r['success_rate'])}, confidently wrong "
        f"{_pct(r['confidently_wrong_rate'])} of {r['converged_steps']} converged steps",
        highlight=False,
    )


def _print_rooms(data: dict[str, Any], title: str) -> None:
    """The ``--random-rooms`` table: one row per generated room, then the pooled numbers."""
    t = table(
        title,
        ("room", "size [m]", "obst.", "refl.", "kinds", "success [%]", "coll. [%]",
         "conv. [%]", "conf. wrong [%]", "wrong/conv."),
    )  # fmt: skip
    for r in data["per_room"]:
        t.add_row(
            str(r["seed"]),
            f"{r['size_m'][0]:.1f} x {r['size_m'][1]:.1f}",
            str(r["obstacles"]),
            str(r["reflectors"]),
            r["kinds"],
            *(_pct(r[k], "") for k in ("success_rate", "collision_rate", "converged_share")),
            _pct(r["confidently_wrong_rate"], ""),
            f"{r['wrong_converged_steps']}/{r['converged_steps']}",
        )
    console.print(t)
    p = data["pooled"]
    console.print(
        f"pooled over {p['episodes']} episodes in {data['rooms']} rooms: success "
        f"{_pct(p['success_rate'])}, collisions {_pct(p['collision_rate'])}, localised "
        f"{_pct(p['time_localised'])}, converged {_pct(p['converged_share'])}, confidently "
        f"wrong {_pct(p['confidently_wrong_rate'])} ({data['wrong_converged_steps']}/"
        f"{data['converged_steps']} converged steps), stuck {_pct(p['stuck_wrong_rate'])}; "
        f"{data['rooms_confidently_wrong_over_1pct']} of {data['rooms']} rooms confidently "
        "wrong over 1 %",
        highlight=False,
    )
