"""lrp-gym: indoor positioning with an FMCW radar and passive retroreflectors (LRPs).

The pipeline, one folder per stage: ``world`` (room, reflectors, robot), ``radar`` (image-source
channel, FMCW signal, range-Doppler processing, CFAR), ``tracking`` (LRP identification and
Kalman tracking), ``placement`` (fingerprint ambiguity and layout search), ``localization``
(look-up table and AMCL) and ``envs`` (the Gymnasium environment ``LRPRadarNav-v0``).
"""

from lrp_gym.config import ScenarioConfig, ScenarioError, load_scenario, save_scenario

__version__ = "0.1.0"

__all__ = ["ScenarioConfig", "ScenarioError", "__version__", "load_scenario", "save_scenario"]

# Registers LRPRadarNav-v0 and its variants with gymnasium (also in fresh worker processes,
# through gym.make("lrp_gym:LRPRadarNav-v0")).
from lrp_gym import envs as _envs  # noqa: E402,F401
