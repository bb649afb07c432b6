"""FMCW derivations pinned to the paper's radar numbers."""

from __future__ import annotations

import pytest

from lrp_gym.waveform import FmcwParameters

# The paper rounds c to 3e8 m/s; we use the exact speed of light, hence rel=2e-3.
REL = 2e-3


def test_paper_waveform_derived_numbers():
    fm = FmcwParameters()
    assert fm.bandwidth_hz == 2e9
    assert fm.chirp_period_s == 220e-6
    assert (fm.samples_per_chirp, fm.chirps_per_frame) == (256, 32)
    assert fm.range_resolution_m == pytest.approx(0.075, rel=REL)
    assert fm.max_range_m == pytest.approx(19.125, rel=REL)
    assert fm.max_velocity_mps == pytest.approx(5.6816, rel=REL)
    assert fm.velocity_resolution_mps == pytest.approx(0.3551, rel=REL)
    assert fm.wavelength_m == pytest.approx(5e-3, rel=REL)
    assert fm.sample_rate_hz == pytest.approx(1.1636e6, rel=1e-3)
    assert fm.frame_time_s == pytest.approx(7.04e-3)


def test_requirements_give_back_the_paper_waveform():
    fm = FmcwParameters.from_requirements(
        range_resolution_m=0.075,
        max_range_m=19.125,
        velocity_resolution_mps=0.3551,
        max_velocity_mps=5.6816,
    )
    assert fm.bandwidth_hz == pytest.approx(2e9, rel=REL)
    assert fm.chirp_period_s == pytest.approx(220e-6, rel=REL)
    assert fm.samples_per_chirp == 256
    assert fm.chirps_per_frame == 32


@pytest.mark.parametrize("res", [0.02, 0.05, 0.1, 0.3])
def test_round_trip_through_requirements(res):
    fm = FmcwParameters.from_requirements(
        range_resolution_m=res, max_range_m=12.0, velocity_resolution_mps=0.2, max_velocity_mps=3.0
    )
    assert fm.range_resolution_m == pytest.approx(res)
    assert fm.max_range_m >= 12.0 > fm.max_range_m - res - 1e-9
    assert fm.velocity_resolution_mps <= 0.2 + 1e-12
    back = FmcwParameters(
        fm.carrier_hz, fm.bandwidth_hz, fm.chirp_period_s, fm.samples_per_chirp, fm.chirps_per_frame
    )
    assert back == fm


def test_requirements_reject_non_positive():
    with pytest.raises(ValueError, match="max_range_m"):
        FmcwParameters.from_requirements(
            range_resolution_m=0.1, max_range_m=0, velocity_resolution_mps=0.1, max_velocity_mps=1
        )
