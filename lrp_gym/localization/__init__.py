"""Positioning from LRP fingerprints: look-up table and AMCL."""

from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.estimate import PoseEstimate
from lrp_gym.localization.lut import LookupTable

__all__ = ["Amcl", "LookupTable", "PoseEstimate"]
