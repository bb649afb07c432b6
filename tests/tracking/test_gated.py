"""The tracker's gated fingerprint: every reflector-like detection of the frame."""

from __future__ import annotations

import numpy as np

from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.tracker import LrpTracker


def test_gated_fingerprint_keeps_window_passing_detections(paper_world, paper_cfg):
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    peak = paper_world.layout.types[0].rcs_dbsm
    det = Detections(
        range_m=[3.1, 4.2, 4.9, 0.8, 5.5, 12.0],
        velocity_mps=[0.1, -0.2, 0.0, 0.0, 0.3, 0.0],
        power_dbm=np.full(6, -70.0),
        rcs_dbsm=[peak, peak - 2, peak + 30, peak, peak - 40, peak],  # 3rd too strong, 5th too weak
        snr_db=np.full(6, 40.0),
    )
    fp = tracker.update(det, 0.25)
    gated = tracker.gated_fingerprint()
    # 0.8 m is nearer than any reflector can be, 12 m farther than the room allows.
    assert np.allclose(gated.distances_m[0], [3.1, 4.2])
    assert gated.fresh[0].all()
    assert len(fp.distances_m[0]) <= len(paper_world.layout)
    tracker.reset()
    assert tracker.gated_fingerprint().count == 0
