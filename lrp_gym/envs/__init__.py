"""Gymnasium environments. Importing :mod:`lrp_gym` registers them.

==========================  =========================================================
id                          what differs
==========================  =========================================================
``LRPRadarNav-v0``          signal-level radar (FMCW beat signal, FFT, CFAR)
``LRPRadarNavFast-v0``      detections-level radar drawn from the channel's paths
``LRPRadarNavOracle-v0``    observation from the true pose (ablation)
==========================  =========================================================

Every id also has a native vector env (``gym.make_vec(id, num_envs=N)``, the default
vectorisation; :mod:`lrp_gym.envs.vector_env`): N robots of one scenario in one batch.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from lrp_gym.config.task import DEFAULT_MAX_EPISODE_STEPS

#: Episodes are truncated by the env at the scenario's ``task.max_episode_steps`` (default
#: 200), not by a ``TimeLimit`` wrapper from the registration, so a patrol scenario sets its own.
MAX_EPISODE_STEPS = DEFAULT_MAX_EPISODE_STEPS

ENV_VARIANTS: dict[str, dict] = {
    "LRPRadarNav-v0": {},
    "LRPRadarNavFast-v0": {"radar_fidelity": "detections"},
    "LRPRadarNavOracle-v0": {"observation": "oracle"},
}


def register_envs() -> None:
    """Register every variant once (safe to call again, e.g. in spawned workers)."""
    for env_id, kwargs in ENV_VARIANTS.items():
        if env_id not in registry:
            register(
                id=env_id,
                entry_point="lrp_gym.envs.nav_env:LRPRadarNavEnv",
                vector_entry_point="lrp_gym.envs.vector_env:LRPRadarNavVectorEnv",
                kwargs=kwargs,
            )


register_envs()
