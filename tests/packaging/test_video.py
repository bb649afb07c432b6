"""The video extra: gymnasium's RecordVideo writes an MP4 of the env's rgb_array frames."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import lrp_gym  # noqa: F401  (registers the env ids)

# make install adds the video extra, so this runs in the test suite.
pytest.importorskip("moviepy", reason="pip install lrp-gym[video]")


def test_record_video_writes_an_mp4(tmp_path):
    env = gym.make("LRPRadarNavFast-v0", render_mode="rgb_array")
    frame_shape = None
    with gym.wrappers.RecordVideo(
        env, str(tmp_path / "videos"), episode_trigger=lambda _: True, disable_logger=True
    ) as rec:
        rec.reset(seed=0)
        for _ in range(4):
            rec.step(np.zeros(2, dtype=np.float32))
        frame_shape = rec.render().shape
    assert len(frame_shape) == 3 and frame_shape[2] == 3
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000
