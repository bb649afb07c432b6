"""LRP identification (RCS and range windows) and Kalman tracking of the reflector distances."""

from lrp_gym.tracking.classify import LrpClassifier, range_limits
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.range_prediction import EgoMotion
from lrp_gym.tracking.tracker import LrpTracker, TrackView

__all__ = [
    "DistancePrior",
    "EgoMotion",
    "Fingerprint",
    "LrpClassifier",
    "LrpTracker",
    "TrackView",
    "range_limits",
]
