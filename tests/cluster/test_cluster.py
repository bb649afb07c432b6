"""Ray as an option: never imported unless asked for, a clear message when missing, the
``--ray [ADDRESS]`` grammar, and the sidecar of partial results (no Ray needed here)."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from lrp_gym.cli import main
from lrp_gym.commands._common import fill_optional_values
from lrp_gym.experiments import cluster
from lrp_gym.experiments.distributed import episode_from_json, episode_to_json
from lrp_gym.experiments.episodes import episode_results, make_eval_env


def run(capsys, *argv):
    with pytest.raises(SystemExit) as exc:
        main(list(argv))
    out, err = capsys.readouterr()
    return exc.value.code, out, err


def test_cli_never_imports_ray():
    code = (
        "import sys, lrp_gym, lrp_gym.cli\n"
        "try:\n    lrp_gym.cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
        "for name in ('robustness', 'layout', 'evaluate'):\n"
        "    try:\n        lrp_gym.cli.main([name, '--help'])\n    except SystemExit:\n        pass\n"
        "print('ray' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "False"


@pytest.mark.parametrize(
    "argv",
    [
        ["robustness", "--ray", "--episodes", "1"],
        ["layout", "--candidates", "3", "--ray", "auto"],
        ["evaluate", "--episodes", "1", "--ray"],
    ],
)
def test_missing_extra_is_one_line_naming_the_install(argv, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: --ray:") and "pip install lrp-gym[cluster]" in err
    assert len(err.strip().splitlines()) == 1


def test_bare_ray_means_local():
    own = {"--ray", "--episodes"}
    assert fill_optional_values(["--ray"], own) == ["--ray", "local"]
    assert fill_optional_values(["--ray", "--episodes", "5"], own) == [
        "--ray",
        "local",
        "--episodes",
        "5",
    ]
    assert fill_optional_values(["--ray", "auto"], own) == ["--ray", "auto"]
    assert fill_optional_values(["--ray=10.0.0.2:6379"], own) == ["--ray=10.0.0.2:6379"]
    assert fill_optional_values(["--ray"], {"--episodes"}) == ["--ray"]  # not this command's
    assert fill_optional_values(["--", "--ray"], own) == ["--", "--ray"]


def test_bad_address_and_resume_without_ray(capsys):
    code, _, err = run(capsys, "robustness", "--ray", "ipin2023")
    assert code == 2 and err.startswith("error: --ray:") and "HOST:PORT" in err
    code, _, err = run(capsys, "robustness", "--resume")
    assert code == 2 and err.startswith("error: --resume:") and "--ray" in err
    code, _, err = run(capsys, "layout", "--ray", "--method", "optimize")
    assert code == 2 and err.startswith("error: --ray:") and "random" in err


def test_an_address_nothing_answers_at_fails_fast(capsys):
    """ray.init retries an unreachable cluster for minutes; the CLI says so at once (a
    loopback port that was just freed, so nothing listens there)."""
    pytest.importorskip("ray")  # the CLI checks that the extra is there first
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = time.monotonic()
    with pytest.raises(ValueError, match=r"address: no Ray cluster answers at '127\.0\.0\.1:"):
        cluster.probe(f"127.0.0.1:{port}")
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--episodes", "1", "--ray", f"127.0.0.1:{port}"])
    assert exc.value.code == 2
    assert "error: --ray: no Ray cluster answers" in capsys.readouterr().err
    assert time.monotonic() - start < 2 * cluster.PROBE_TIMEOUT_S


def test_episode_results_survive_the_sidecar_exactly():
    cell = {"perturbations": {"kidnapping": {"severity": 1.0}}, "radar": {"fidelity": "detections"}}
    env = make_eval_env("oracle", None, "ipin2023", overrides=cell)
    from agents.pure_pursuit import PurePursuitPolicy

    (r,) = episode_results(env, PurePursuitPolicy.from_env(env), [3])
    back = episode_from_json(json.loads(json.dumps(episode_to_json(r))))
    assert r.kidnap_frame is not None and back.kidnap_frame == r.kidnap_frame
    assert back.row() == r.row() and back.suspect_first_frame == r.suspect_first_frame
    for name in ("loc_error_m", "converged", "true_xy", "est_xy", "confidence"):
        a, b = getattr(r, name), getattr(back, name)
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_run_units_resumes_from_the_sidecar(tmp_path):
    side = cluster.Sidecar(tmp_path / "r.json.partial.jsonl", {"study": 1})
    units = [(f"u{i}", i) for i in range(4)]
    ran: list[int] = []

    def task(i):
        ran.append(i)
        return [i, i * i]

    full = cluster.run_units(task, units, None, side)
    lines = side.path.read_text().splitlines()
    assert full == [[0, 0], [1, 1], [2, 4], [3, 9]] and len(lines) == 5
    side.path.write_text("\n".join(lines[:3]) + "\n" + lines[3][:10])  # killed mid-line
    ran.clear()
    assert cluster.run_units(task, units, None, side, resume=True) == full
    assert ran == [2, 3]
    with pytest.raises(ValueError, match="another study"):
        cluster.Sidecar(side.path, {"study": 2}).load()


def test_partial_results_need_resume_or_force(tmp_path, capsys):
    pytest.importorskip("ray")
    out = tmp_path / "m.json"
    cluster.sidecar_path(out).write_text('{"format": "x"}\n')
    argv = ["robustness", "--ray", "--episodes", "1", "--out", str(out)]
    code, _, err = run(capsys, *argv)
    assert code == 2 and err.startswith("error: --out:") and "--resume" in err
    code, _, err = run(capsys, *argv, "--resume")
    assert code == 2 and err.startswith("error: --resume:") and "another study" in err


def test_sweep_file_problems_name_the_key(tmp_path, capsys, monkeypatch):
    bad = tmp_path / "s.yaml"
    bad.write_text("timesteps: 64\nseeds: [0]\ngrid: {learning_rate: []}\n")
    code, _, err = run(capsys, "sweep", str(bad), "--out", str(tmp_path / "o"))
    assert code == 2 and err.startswith("error: CONFIG:") and "grid:" in err
    bad.write_text("timesteps: 64\nlearning_rate: 0.1\n")
    code, _, err = run(capsys, "sweep", str(bad), "--out", str(tmp_path / "o"))
    assert code == 2 and "unknown key(s) learning_rate" in err
    monkeypatch.setitem(sys.modules, "ray", None)
    good = "configs/sweep-smoke.yaml"
    code, _, err = run(capsys, "sweep", good, "--out", str(tmp_path / "o"))
    assert code == 2 and "pip install lrp-gym[cluster]" in err
    assert not (tmp_path / "o").exists()  # nothing started
