"""Robustness perturbations: what can go wrong between the room and the pose estimate.

Each perturbation is one small class (:class:`~lrp_gym.perturbations.base.Perturbation`) with
hooks the env calls; it is switched on by its section in the scenario's ``perturbations:``
(or ``overrides={"perturbations": {...}}``), validated by the pydantic models in
:mod:`lrp_gym.config`. Every one has a ``severity`` in [0, 1] that sets its physical
parameters, so a perturbation x severity matrix compares like with like.

=======================  ==========================================================  =========
name                     effect                                                      severity 1
=======================  ==========================================================  =========
``shadowing``            reflectors hidden for N frames (static or walking person)   40 frames
``missed_detections``    each detection dropped with probability p                   p = 1
``clutter``              static point scatterers with reflector-like RCS             20
``displaced_reflector``  a reflector moved; the localiser keeps the surveyed map      1 m
``odometry_slip``        reported distance x (1 + slip), heading bias                0.5, 20 deg/s
``kidnapping``           true pose teleported once, localiser not told               >= 3 m
``interference``         bursts of spurious detections (another radar)               p 0.3, 10/frame
``incidence_angle``      narrower reflector acceptance angle                         10/36 deg
=======================  ==========================================================  =========
"""

from lrp_gym.perturbations import layout, robot_motion, sensing  # noqa: F401  (registers the classes)
from lrp_gym.perturbations.base import REGISTRY, FrameContext, Perturbation, register
from lrp_gym.perturbations.composite import PerturbationSet

#: perturbation names in the order their hooks run
NAMES = tuple(REGISTRY)

__all__ = ["NAMES", "REGISTRY", "FrameContext", "Perturbation", "PerturbationSet", "register"]
