"""On a local Ray (2 CPUs, started once for this file): the same results as the one-process
run, to the byte, and an interrupted study completed with ``--resume`` running only what is
missing."""

from __future__ import annotations

import json

import pytest

from lrp_gym.cli import main
from lrp_gym.experiments import cluster

ray = pytest.importorskip("ray")
pytestmark = pytest.mark.ray

MATRIX = ["robustness", "--fidelity", "detections", "--episodes", "7", "--seed", "4"]
MATRIX += ["--perturbations", "kidnapping", "--severities", "1"]  # 2 cells x 2 tasks of 5 + 2


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    cluster.connect("local", num_cpus=2)
    yield
    ray.shutdown()


def run(capsys, *argv):
    with pytest.raises(SystemExit) as exc:
        main(list(argv))
    out, err = capsys.readouterr()
    assert exc.value.code == 0, err
    return out


@pytest.fixture(scope="module")
def local_matrix(tmp_path_factory):
    path = tmp_path_factory.mktemp("local") / "m.json"
    with pytest.raises(SystemExit):
        main([*MATRIX, "--out", str(path)])
    return path.read_bytes()


def test_matrix_on_ray_equals_local_then_resumes(local_matrix, tmp_path, capsys, monkeypatch):
    out = tmp_path / "m.json"
    side = cluster.sidecar_path(out)
    monkeypatch.setattr(cluster.Sidecar, "remove", lambda self: None)  # keep it to cut it short
    run(capsys, *MATRIX, "--ray", "--out", str(out))
    assert out.read_bytes() == local_matrix
    doc = json.loads(local_matrix)
    assert [c["perturbation"] for c in doc["cells"]] == ["none", "kidnapping"]
    assert doc["cells"][1]["kidnapped_episodes"] == 7
    lines = side.read_text().splitlines()
    keys = sorted(json.loads(line)["unit"] for line in lines[1:])
    assert keys == sorted(
        f"{cell}/seeds {a}-{b}"
        for cell in ("baseline", "kidnapping @ 1")
        for a, b in ((4, 8), (9, 10))
    )
    # An interrupted study: two tasks finished, a third cut off while being written.
    side.write_text("\n".join(lines[:3]) + "\n" + lines[3][:40])
    out.unlink()
    monkeypatch.undo()  # the real remove() again
    ran: list[str] = []
    append = cluster.Sidecar.append
    monkeypatch.setattr(
        cluster.Sidecar, "append", lambda self, k, r: (ran.append(k), append(self, k, r))
    )
    run(capsys, *MATRIX, "--ray", "--out", str(out), "--resume")
    kept = {json.loads(line)["unit"] for line in lines[1:3]}
    assert sorted(ran) == sorted(set(keys) - kept)
    assert out.read_bytes() == local_matrix
    assert not side.exists()  # the result is whole: the partial results are gone


def test_layout_search_on_ray_equals_local(capsys):
    argv = ["layout", "--candidates", "120", "--seed", "2", "--json"]
    local, on_ray = json.loads(run(capsys, *argv)), json.loads(run(capsys, *argv, "--ray"))
    local.pop("search_s"), on_ray.pop("search_s")  # wall times
    assert on_ray == local and local["evaluations"] == 120


def test_evaluate_on_ray_equals_local(capsys, tmp_path, monkeypatch):
    from lrp_gym.config import SCENARIOS_DIR

    (tmp_path / "room.yaml").write_text((SCENARIOS_DIR / "ipin2023.yaml").read_text())
    monkeypatch.chdir(tmp_path)  # a scenario file named relative to the driver's folder
    argv = ["evaluate", "room.yaml", "--fidelity", "detections", "--task", "goal"]
    argv += ["--episodes", "6", "--seed", "30", "--json"]
    local = run(capsys, *argv)
    assert run(capsys, *argv, "--ray", "auto") == local  # the Ray this process runs
    assert [r["seed"] for r in json.loads(local)["per_episode"]] == list(range(30, 36))


def test_workers_import_this_checkout():
    import lrp_gym

    def where(_unit):  # nested: pickled by value (workers cannot import the tests)
        import lrp_gym

        return lrp_gym.__file__

    # A checkout run with PYTHONPATH may sit beside another installed copy: the workers must
    # import the driver's, or their numbers would be another version's.
    assert cluster.run_units(where, [("a", 0), ("b", 1)], "local") == [lrp_gym.__file__] * 2


def test_reproduce_runs_on_ray_equal_local(capsys):
    argv = ["reproduce-paper", "--runs", "3", "--fidelity", "detections", "--noise", "--json"]
    local, on_ray = json.loads(run(capsys, *argv)), json.loads(run(capsys, *argv, "--ray"))
    for doc in (local, on_ray):  # wall times
        doc.pop("frame_ms"), doc.pop("lut_build_s")
    assert on_ray == local and local["runs"] == 3
