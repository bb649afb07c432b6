"""Chirp-sequence FMCW waveform parameters and the figures derived from them."""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.constants import speed_of_light as C


@dataclass(frozen=True)
class FmcwParameters:
    """Chirp-sequence FMCW waveform.

    Complex baseband sampling: ``samples_per_chirp`` samples spread over one chirp period, so
    the sample rate is ``samples_per_chirp / chirp_period_s`` and every range bin is
    unambiguous.

    Parameters
    ----------
    carrier_hz : float
        Carrier frequency f_c.
    bandwidth_hz : float
        Swept bandwidth B.
    chirp_period_s : float
        Chirp repetition period T_c (also the sampled ramp duration).
    samples_per_chirp : int
        N_s complex samples per chirp.
    chirps_per_frame : int
        N_c chirps per frame.
    """

    carrier_hz: float = 60e9
    bandwidth_hz: float = 2e9
    chirp_period_s: float = 220e-6
    samples_per_chirp: int = 256
    chirps_per_frame: int = 32

    @property
    def wavelength_m(self) -> float:
        return C / self.carrier_hz

    @property
    def sample_rate_hz(self) -> float:
        return self.samples_per_chirp / self.chirp_period_s

    @property
    def range_resolution_m(self) -> float:
        """Range bin width c / (2 B)."""
        return C / (2.0 * self.bandwidth_hz)

    @property
    def max_range_m(self) -> float:
        """Range of the last range bin, (N_s - 1) c / (2 B)."""
        return (self.samples_per_chirp - 1) * self.range_resolution_m

    @property
    def max_velocity_mps(self) -> float:
        """Unambiguous radial velocity span is [-v_max, v_max) with v_max = lambda / (4 T_c)."""
        return self.wavelength_m / (4.0 * self.chirp_period_s)

    @property
    def velocity_resolution_mps(self) -> float:
        """Doppler bin width 2 v_max / N_c = lambda / (2 N_c T_c)."""
        return 2.0 * self.max_velocity_mps / self.chirps_per_frame

    @property
    def frame_time_s(self) -> float:
        """Duration of one chirp sequence, N_c T_c."""
        return self.chirps_per_frame * self.chirp_period_s

    @classmethod
    def from_requirements(
        cls,
        *,
        range_resolution_m: float,
        max_range_m: float,
        velocity_resolution_mps: float,
        max_velocity_mps: float,
        carrier_hz: float = 60e9,
    ) -> FmcwParameters:
        """Smallest waveform that meets the wanted resolutions and spans.

        ``samples_per_chirp`` and ``chirps_per_frame`` are rounded up, so the delivered spans
        are at least those asked for; resolutions are met exactly.
        """
        for name, value in {
            "range_resolution_m": range_resolution_m,
            "max_range_m": max_range_m,
            "velocity_resolution_mps": velocity_resolution_mps,
            "max_velocity_mps": max_velocity_mps,
            "carrier_hz": carrier_hz,
        }.items():
            if not value > 0:
                raise ValueError(f"{name} must be positive, got {value}")
        bandwidth = C / (2.0 * range_resolution_m)
        wavelength = C / carrier_hz
        chirp_period = wavelength / (4.0 * max_velocity_mps)
        samples = math.ceil(max_range_m / range_resolution_m - 1e-9) + 1
        chirps = math.ceil(2.0 * max_velocity_mps / velocity_resolution_mps - 1e-9)
        return cls(carrier_hz, bandwidth, chirp_period, samples, chirps)

    def summary(self) -> dict[str, float]:
        """Derived figures, keyed by name with units."""
        return {
            "wavelength_m": self.wavelength_m,
            "bandwidth_hz": self.bandwidth_hz,
            "chirp_period_s": self.chirp_period_s,
            "sample_rate_hz": self.sample_rate_hz,
            "samples_per_chirp": self.samples_per_chirp,
            "chirps_per_frame": self.chirps_per_frame,
            "range_resolution_m": self.range_resolution_m,
            "max_range_m": self.max_range_m,
            "velocity_resolution_mps": self.velocity_resolution_mps,
            "max_velocity_mps": self.max_velocity_mps,
            "frame_time_s": self.frame_time_s,
        }
