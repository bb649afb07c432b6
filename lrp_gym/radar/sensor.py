"""The radar sensor the rest of the project uses: pose in, detections out.

Two fidelities (``radar.fidelity``):

- ``signal``: channel paths -> beat-signal cube with thermal noise -> window, 2-D FFT -> CFAR ->
  peak interpolation -> range, velocity, power, RCS, SNR.
- ``detections``: detections drawn straight from the paths by :mod:`lrp_gym.radar.detection_model`, with
  the resolution, interpolation error and detection probability of the signal model.
"""

from __future__ import annotations

import math

import numpy as np

from lrp_gym.config import RadarConfig
from lrp_gym.radar.antenna import ZenithPattern
from lrp_gym.radar.cfar import Cfar2D
from lrp_gym.radar.channel import Channel
from lrp_gym.radar.detection_model import FastDetectionModel
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.frontend import beat_cube, link_constant_w_m2, noise_power_w
from lrp_gym.radar.paths import Paths
from lrp_gym.radar.processing import RangeDopplerProcessor
from lrp_gym.world.world import World

FOUR_PI = 4.0 * np.pi


class RadarSensor:
    """FMCW radar on the robot.

    Parameters
    ----------
    world : World
        Room, reflectors, waveform and mount height.
    radar : RadarConfig
        Link budget, noise, window, CFAR, reflection order and fidelity.

    Attributes
    ----------
    last_map_db : ndarray (N_s, N_c) or None
        Range-Doppler power map of the last signal-level frame, in dBm at the antenna port
        (map power divided by the window's coherent gain).
    last_paths : Paths or None
        Propagation paths of the last frame.
    """

    def __init__(self, world: World, radar: RadarConfig) -> None:
        self.world = world
        self.config = radar
        self.fmcw = world.fmcw
        self.fidelity = radar.fidelity
        self.link_w_m2 = link_constant_w_m2(
            radar.tx_power_dbm, radar.tx_gain_dbi, radar.rx_gain_dbi, self.fmcw.wavelength_m
        )
        self.noise_w = noise_power_w(self.fmcw, radar.noise_figure_db, radar.temperature_k)
        self.noise_on = bool(radar.noise)
        # Paths 90 dB below the per-sample noise cannot show in the map (50 dB below a
        # cell's noise); dropping them also keeps float32 clear of denormals.
        self.min_path_power_w = 1e-9 * self.noise_w
        self.channel = Channel(
            world.room,
            world.layout,
            self.fmcw.wavelength_m,
            self.link_w_m2,
            radar.max_reflection_order,
            body_shadowing=radar.body_shadowing,
            antenna=(
                ZenithPattern(radar.antenna_half_power_deg, radar.antenna_floor_db)
                if radar.antenna_half_power_deg is not None
                else None
            ),
            min_power_w=self.min_path_power_w,
        )
        self.cfar = Cfar2D.from_config(radar.cfar)
        self.processor = RangeDopplerProcessor(self.fmcw, radar.window, self.cfar)
        #: noise power of one map cell (the noise level in map units, also with noise off)
        self.noise_cell = self.noise_w * self.processor.noise_gain
        #: cells at or below this map power are not CFAR-tested (no measurable effect on Pfa)
        self.prethreshold = self.cfar.alpha * self.cfar.prethreshold_fraction * self.noise_cell
        self.min_range_m = radar.min_range_m
        self._last_map: np.ndarray | None = None
        self.last_paths: Paths | None = None
        self._fast = None
        if self.fidelity == "detections":
            self._fast = FastDetectionModel.for_sensor(self)

    @property
    def last_map_db(self) -> np.ndarray | None:
        """The last signal-level map in dBm at the antenna (computed on access: the env's step
        never needs it, plots do)."""
        if self._last_map is None:
            return None
        return (
            10.0 * np.log10(np.maximum(self._last_map, 1e-30) / self.processor.coherent_gain2)
            + 30.0
        )

    # ------------------------------------------------------------------ conversions
    def rcs_dbsm(self, power_w: np.ndarray, range_m: np.ndarray) -> np.ndarray:
        """Invert the radar equation: RCS from received power and range.

        With an antenna pattern the two-way gain is undone for the zenith angle a target at
        the reflectors' mean height would have at that range (only those need a fair RCS).
        """
        r = np.maximum(np.asarray(range_m, float), 1e-6)
        sigma = np.asarray(power_w) * FOUR_PI**3 * r**4 / self.link_w_m2
        antenna = self.channel.antenna
        if antenna is not None and len(self.world.layout):
            dz = float(np.mean(self.world.layout.positions_m[:, 2])) - self.world.mount_height_m
            sigma = sigma / antenna.gain(np.clip(dz / r, -1.0, 1.0)) ** 2
        return 10.0 * np.log10(np.maximum(sigma, 1e-30))

    def paths(
        self,
        pose: np.ndarray,
        velocity_xy_mps: np.ndarray,
        *,
        hidden: np.ndarray | None = None,
        extra_scatterers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Paths:
        """Propagation paths for a robot pose (x, y, theta) within the unambiguous range."""
        pose = np.asarray(pose, float)
        radar = np.array([pose[0], pose[1], self.world.mount_height_m])
        p = self.channel.paths(
            radar,
            np.asarray(velocity_xy_mps, float),
            hidden=hidden,
            extra_scatterers=extra_scatterers,
        )
        return p.select((p.range_m <= self.fmcw.max_range_m) & (p.power_w > self.min_path_power_w))

    def measure(
        self,
        pose: np.ndarray,
        velocity_xy_mps: np.ndarray,
        rng: np.random.Generator,
        *,
        hidden: np.ndarray | None = None,
        extra_scatterers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Detections:
        """One radar frame at ``pose`` (x, y, theta) moving at ``velocity_xy_mps`` (2,).

        The radar sits at ``(x, y, mount_height_m)``. All randomness comes from ``rng``.
        """
        paths = self.paths(pose, velocity_xy_mps, hidden=hidden, extra_scatterers=extra_scatterers)
        self.last_paths = paths
        return self.detect(paths, rng)

    def detect(self, paths: Paths, rng: np.random.Generator) -> Detections:
        """The detections of given ``paths`` at this sensor's fidelity."""
        if self._fast is not None:
            self._last_map = None
            return self._fast.detect(paths, rng)
        return self.process(paths, rng)

    def process(self, paths: Paths, rng: np.random.Generator | None) -> Detections:
        """Signal-level chain for given paths."""
        fm = self.fmcw
        noise = self.noise_w if self.noise_on else 0.0
        cube = beat_cube(
            fm,
            paths.range_m,
            paths.velocity_mps,
            paths.power_w,
            paths.phase_rad,
            noise_w=noise,
            rng=rng,
        )
        pmap = self.processor.power_map(cube)
        self._last_map = pmap
        # Noise-free maps: an ideal known-noise floor keeps float round-off from detecting.
        floor = 0.0 if self.noise_on else -math.log(self.cfar.pfa) * self.noise_cell
        pk = self.processor.peaks(pmap, floor, self.prethreshold)
        nc = fm.chirps_per_frame
        vel = (pk.doppler_bin - nc // 2) * fm.velocity_resolution_mps
        vmax = fm.max_velocity_mps
        vel = (vel + vmax) % (2.0 * vmax) - vmax
        # Undo the range-Doppler coupling with the measured velocity.
        coupling_bins = 2.0 * vel * fm.chirp_period_s / fm.wavelength_m
        rng_m = (pk.range_bin - coupling_bins) * fm.range_resolution_m
        keep = rng_m >= self.min_range_m
        power = pk.power_at_antenna_w[keep]
        rng_m = rng_m[keep]
        return Detections(
            range_m=rng_m,
            velocity_mps=vel[keep],
            power_dbm=10.0 * np.log10(power) + 30.0,
            rcs_dbsm=self.rcs_dbsm(power, rng_m),
            snr_db=10.0 * np.log10(pk.peak_power[keep] / self.noise_cell),
        )
