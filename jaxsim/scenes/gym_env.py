"""Gymnasium adapters of the JAX environment, numpy in and out, for Stable-Baselines3- and
CleanRL-style code (``pip install socialnav-jax[gym]``).

* :class:`SocialNavEnv`: one ``gymnasium.Env`` (passes ``gymnasium.utils.env_checker.check_env``).
* :class:`SocialNavVectorEnv`: a ``gymnasium.vector.VectorEnv`` of ``num_envs`` episodes stepped
  as one jitted ``vmap`` (gymnasium's default next-step autoreset: the step after an episode ends
  returns the new episode's first observation with reward 0).

Observations are a ``Dict`` of float32 boxes, one per :class:`~jaxsim.scenes.env.Observation`
field (``people_visible`` as 0/1); the action is ``Box([0, -w_max], [v_max, w_max])``. An action
of another shape is refused with a ``ValueError`` naming it; one with a NaN or infinite entry
stops the robot for that step, as the JAX environment does, and ``info["invalid_action"]`` says
so (the observation stays finite and inside its space). ``info["person_contact"]`` says the robot
touched a person on the step and ``info["rule_kept"]`` that the scene's social rule has been kept
so far (:class:`jaxsim.scenes.wrappers.RuleMonitor`): on a ``terminated`` step (the goal), the
arena's social success. A scene no method can finish with the env's robot (its goal walled off,
a rule box the robot cannot enter, a ``timeout_s`` shorter than the straight line at top speed
where no ``config`` sets the episodes' length: :func:`jaxsim.scenes.reachable.scene_problem`) is
refused when the adapter is made, with a :class:`~jaxsim.scenario.errors.ScenarioError` naming
the file and field, as ``socialnav arena`` refuses it. Each
reset draws a variant of the scene from a pool drawn once (``pool`` variants under ``seed``,
the scene's training draws, never the held-out ones); ``reset(seed=s)`` reseeds the choice.
"""

from __future__ import annotations

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes import wrappers
from socialnav.jaxsim.scenes.reachable import refuse_unfinishable
from socialnav.jaxsim.scenes.spec import SceneSpec
from socialnav.jaxsim.scenes.variant import padded_slots, sample_variants

# Bounds of the unbounded fields (the yaw is not wrapped: it counts whole turns).
_BOUND = {
    "robot_speed_mps": (-10.0, 10.0),
    "robot_turn_rate_rps": (-10.0, 10.0),
    "people_velocity_mps": (-20.0, 20.0),
    "people_heading_rad": (-4.0, 4.0),
}


def observation_space(env: env_lib.Env, n_people: int) -> spaces.Dict:
    """The gymnasium space of one observation."""
    fields = {}
    for spec in jax.tree.leaves(env.observation_spec(n_people)):
        if spec.dtype == jnp.bool_ or spec.name == "occupancy":
            lo, hi = 0.0, 1.0
        else:
            lo, hi = _BOUND.get(spec.name, (-1e4, 1e4))
        fields[spec.name] = spaces.Box(lo, hi, spec.shape, np.float32)
    return spaces.Dict(fields)


def action_space(env: env_lib.Env) -> spaces.Box:
    spec = env.action_spec()
    return spaces.Box(np.array(spec.minimum, np.float32), np.array(spec.maximum, np.float32), dtype=np.float32)


def _numpy(observation: env_lib.Observation) -> dict[str, np.ndarray]:
    return {k: np.asarray(v, np.float32) for k, v in vars(observation).items()}


class SocialNavVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` episodes of one scene, stepped together (see the module's docstring).

    Args:
      spec: the scene; num_envs: episodes at once; pool: variants to draw resets from; seed:
      the pool's draw; config/robot/reward: the env's settings (:func:`jaxsim.scenes.env.make_env`).
    """

    metadata = {"autoreset_mode": gym.vector.AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        spec: SceneSpec,
        num_envs: int = 8,
        pool: int = 256,
        seed: int = 0,
        config: env_lib.EnvConfig | None = None,
        robot=None,
        reward: env_lib.RewardParams = env_lib.RewardParams(),
    ):
        if num_envs < 1 or pool < 1:
            raise ValueError(f"num_envs and pool must be >= 1, got {num_envs} and {pool}")
        own_time_limit = config is not None
        config = config or env_lib.EnvConfig(max_steps=env_lib.episode_steps(spec.timeout_s, env_lib.EnvConfig.dt_s))
        kwargs = {} if robot is None else {"robot": robot}
        self.env = env_lib.make_env(spec, config, reward=reward, **kwargs)
        # a config's own max_steps is a horizon the caller chose (truncation), not the scene's timeout
        refuse_unfinishable(spec, self.env.robot, config.goal_tolerance_m, not own_time_limit)
        n_slots = padded_slots(spec.n_people_slots)
        variants = sample_variants(spec, seed, pool, 0, False, n_slots)
        self._pool = wrappers.VariantPool(jax.tree_util.tree_map(jnp.asarray, variants))
        env = wrappers.RuleMonitor.of(wrappers.FromPool(self.env, self._pool), spec.rule)
        self.num_envs = num_envs
        self.single_observation_space = observation_space(self.env, n_slots)
        self.single_action_space = action_space(self.env)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._rng = np.random.default_rng(seed)
        self._state = None
        self._needs_reset = np.zeros(num_envs, bool)
        self._reset = jax.jit(jax.vmap(env.reset))

        def step(states, actions, reset_mask, keys, index):
            stepped, ts = jax.vmap(env.step)(states, actions)
            # Gymnasium's next-step autoreset: those that ended on the last step start afresh now.
            return wrappers.reset_where(env, reset_mask, keys, index, stepped, ts)

        self._step = jax.jit(step)

    def _draw(self, n: int):
        keys = jax.random.split(jax.random.key(int(self._rng.integers(2**31))), n)
        return keys, jnp.asarray(self._rng.integers(0, self._pool.size, n))

    def reset(self, *, seed: int | None = None, options=None):
        super().reset(seed=seed)
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        keys, index = self._draw(self.num_envs)
        self._state, ts = self._reset(keys, index)
        self._needs_reset[:] = False
        return _numpy(ts.observation), {}

    def step(self, actions):
        if self._state is None:
            raise RuntimeError("SocialNavVectorEnv.step before reset")
        actions = _as_actions(actions, (self.num_envs, 2), "SocialNavVectorEnv.step")
        keys, index = self._draw(self.num_envs)
        mask = jnp.asarray(self._needs_reset)
        self._state, ts = self._step(self._state, actions, mask, keys, index)
        terminated = np.asarray(ts.terminated) & ~self._needs_reset
        truncated = np.asarray(ts.truncated) & ~self._needs_reset
        reward = np.where(self._needs_reset, 0.0, np.asarray(ts.reward)).astype(np.float32)
        self._needs_reset = terminated | truncated
        info = {
            "invalid_action": np.asarray(ts.info.invalid_action),
            "person_contact": np.asarray(ts.info.person_contact),
            "rule_kept": np.asarray(self._state.extras["rule_kept"]),
        }
        return _numpy(ts.observation), reward, terminated, truncated, info


class SocialNavEnv(gym.Env):
    """One episode at a time: :class:`SocialNavVectorEnv` with ``num_envs = 1``, unbatched."""

    metadata = {"render_modes": []}

    def __init__(self, spec: SceneSpec, pool: int = 256, seed: int = 0, **kwargs):
        self._vector = SocialNavVectorEnv(spec, 1, pool, seed, **kwargs)
        self.observation_space = self._vector.single_observation_space
        self.action_space = self._vector.single_action_space

    def reset(self, *, seed: int | None = None, options=None):
        super().reset(seed=seed)
        obs, info = self._vector.reset(seed=seed)
        return {k: np.asarray(v[0]) for k, v in obs.items()}, info

    def step(self, action):
        action = _as_actions(action, (2,), "SocialNavEnv.step")
        obs, reward, terminated, truncated, info = self._vector.step(action[None])
        return (
            {k: np.asarray(v[0]) for k, v in obs.items()},
            float(reward[0]),
            bool(terminated[0]),
            bool(truncated[0]),
            {k: bool(v[0]) for k, v in info.items()},
        )


def _as_actions(actions, shape: tuple[int, ...], where: str) -> np.ndarray:
    """``actions`` as float32 of ``shape``; ``ValueError`` naming the shape found otherwise
    (a reshape would read a (1,) action as speed = turn rate or fail with numpy's message)."""
    try:
        array = np.asarray(actions, np.float32)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{where}: actions must be numbers of shape {shape} (v m/s, omega rad/s): {e}") from None
    if array.shape != shape:
        raise ValueError(f"{where}: actions must have shape {shape} (v m/s, omega rad/s), got shape {array.shape}")
    return array
