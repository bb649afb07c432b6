"""Positioning from LRP fingerprints: look-up table, AMCL and the histogram (grid) filter."""

from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.factory import Localizer, make_localizer
from lrp_gym.localization.grid import GridFilter
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.pose_estimate import PoseEstimate

__all__ = ["Amcl", "GridFilter", "Localizer", "LookupTable", "PoseEstimate", "make_localizer"]
