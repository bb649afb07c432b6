"""``--set KEY.PATH=VALUE`` scenario overrides shared by the experiment commands."""

from __future__ import annotations

import pytest

from lrp_gym.cli import main
from lrp_gym.commands._common import parse_sets
from lrp_gym.config import ScenarioError, load_scenario
from lrp_gym.errors import InputError


def test_sets_nest_merge_and_read_yaml_values():
    out = parse_sets(
        [
            "localization.measurements=tracks",
            "radar.noise=false",
            "localization.clutter_probability=0.1",
        ]
    )
    assert out == {
        "localization": {"measurements": "tracks", "clutter_probability": 0.1},
        "radar": {"noise": False},
    }
    cfg = load_scenario("ipin2023").with_overrides(out)
    assert cfg.localization.measurements == "tracks" and cfg.radar.noise is False


@pytest.mark.parametrize("item", ["noequals", "=3", "a..b=1", "radar.noise=[unclosed"])
def test_malformed_items_name_the_option(item):
    with pytest.raises(InputError, match="--set"):
        parse_sets([item])


def test_unknown_key_names_the_field():
    with pytest.raises(ScenarioError, match="tracking.bogus"):
        parse_sets(["tracking.bogus=1"])


def test_cli_rejects_a_bad_set_with_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["reproduce-paper", "--runs", "1", "--set", "localization.measurements=maybe"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "localization.measurements" in err and "Traceback" not in err
