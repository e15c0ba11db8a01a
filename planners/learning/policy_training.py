"""PPO in the vectorised arena: the policy of :mod:`planners.learning.policy` trained on many scenes at once.

A single-file PPO in the purejaxrl style (Lu et al. 2022; clipped surrogate, GAE, value
clipping, per-minibatch advantage normalisation, Adam with gradient clipping: Schulman et al.
2017 and the "37 details" of Huang et al. 2022), written here rather than taken from rejax
(0.1.3, the JAX RL library on the registry): rejax trains one gymnax environment of one shape in
one jitted call, while this training steps scenes of different shapes (one compiled collector
per scene, one update over all of their transitions) and must stop and resume between updates
with nothing lost; rejax would also bring gymnax and distrax for a 100-line algorithm.

One update:

1. every scene's ``envs_per_scene`` episodes run ``rollout_steps`` steps under the current
   policy (sampled actions), each ended episode restarting at once on a variant drawn from the
   scene's *training* pool (:func:`jaxsim.scenes.variant.sample_variants` with ``training=True``:
   a stream no evaluation draws from); the rollout is the toolkit's one control loop
   (:func:`jaxsim.control.control_loop`, as the arena's episodes and the warehouse day), the
   policy an actor on the batch (:func:`sampling_actor`) and the batch with its restarts a world
   (:func:`batch_step`);
2. the reward is the env's (CrowdNav's: goal, collision, discomfort, wall contact) with its
   Euclidean progress term replaced by progress along the guidance field (metres of free-space
   path gained; potential-based shaping, Ng et al. 1999, which keeps the optimal policy and,
   unlike the straight-line distance, does not reward driving into the inner wall of a corner);
   a time-limit truncation is treated as an end (purejaxrl's choice);
   each episode's scene rule is checked as it runs (:mod:`jaxsim.scenes.rule_monitor`), so
   the ended episodes' social success (the arena's: goal and rule) is known at every update.
   The pool, the shaping, the rule and the episode's statistics are the env's wrappers
   (:func:`training_env`, :mod:`jaxsim.scenes.wrappers`);
3. advantages by GAE per scene, then ``epochs`` passes of ``minibatches`` shuffled minibatches
   over all scenes' transitions together.

The random keys of update ``u`` are ``fold_in(seed, u)``, so the state between updates
(:class:`TrainState`) is all there is to save: a run resumed from a checkpoint continues with
the same bits as one never stopped (tested).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import struct

from socialnav.common import pytree
from socialnav.common.memory import too_big
from socialnav.jaxsim import humans
from socialnav.jaxsim.actor import Actor
from socialnav.jaxsim.control import control_loop
from socialnav.jaxsim.scenes import env as env_lib
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import wrappers
from socialnav.jaxsim.scenes.people import HUMAN_MODELS
from socialnav.jaxsim.scenes.spec import SceneSpec
from socialnav.jaxsim.scenes.variant import padded_slots, sample_variants
from socialnav.models import policy_net
from socialnav.planners.layers import costmap
from socialnav.planners.learning import policy as policy_lib
from socialnav.planners.learning import policy_social


@dataclasses.dataclass(frozen=True)
class PPOConfig:
    """Training settings (JSON in a run's ``config.json``; a resumed run must match).

    Attributes:
      scenes: the scene names trained on (the built-in scenes by default).
      envs_per_scene, rollout_steps: episodes stepped at once per scene, steps per update
        (64 x 64: 4,096 transitions per scene and update).
      updates: updates in all.
      epochs, minibatches: passes over an update's transitions and the minibatches of a pass.
      learning_rate, max_grad_norm: Adam's step and the global gradient-norm clip.
      gamma, gae_lambda, clip_eps, value_coef, entropy_coef: PPO's (purejaxrl's and CleanRL's
        continuous-control defaults; entropy 0 as theirs).
      progress_weight: reward per metre gained along the guidance field (robot_sf's progress
        term; 0.1 keeps a whole crossing worth about CrowdNav's goal reward of 1).
      pool_per_scene: training variants drawn per scene (resets draw among them).
      seed: the run's seed (network initialisation, pools, every key).
      checkpoint_every: updates between checkpoints.
      policy: the network's and features' shape (:class:`planners.learning.policy.PolicyConfig`).
      human_model: how the people the policy trains among move
        (:data:`jaxsim.scenes.people.HUMAN_MODELS`; the arena's default, the social force, unless
        asked). A run that predates the setting trained among the social force.
      human_values: ``("<part>.<field>", value)`` pairs setting that model's constants (a
        calibration's fit, ``socialnav policy train --human-fit``; empty: the name's own).
    """

    scenes: tuple[str, ...] = ()
    envs_per_scene: int = 64
    rollout_steps: int = 64
    updates: int = 300
    epochs: int = 4
    minibatches: int = 8
    learning_rate: float = 3e-4
    max_grad_norm: float = 0.5
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    value_coef: float = 0.5
    entropy_coef: float = 0.0
    progress_weight: float = 0.1
    pool_per_scene: int = 256
    seed: int = 0
    checkpoint_every: int = 10
    policy: policy_lib.PolicyConfig = policy_lib.PolicyConfig()
    human_model: str = "social_force"
    human_values: tuple[tuple[str, float], ...] = ()

    def __post_init__(self):
        if self.human_model not in HUMAN_MODELS:
            raise ValueError(f"human_model must be one of {', '.join(HUMAN_MODELS)}, got {self.human_model!r}")
        problem = humans.values_problem(self.human_model, dict(self.human_values))
        if problem is not None:
            raise ValueError(f"human_values: {problem}")
        for name in ("envs_per_scene", "rollout_steps", "updates", "epochs", "minibatches", "pool_per_scene"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.checkpoint_every < 1:
            raise ValueError(f"checkpoint_every must be >= 1, got {self.checkpoint_every}")

    def to_json(self) -> dict:
        fitted = {"human_values": dict(self.human_values)} if self.human_values else {}  # absent: as earlier runs
        return {
            **{k: v for k, v in dataclasses.asdict(self).items() if k != "human_values"},
            "scenes": list(self.scenes),
            "policy": self.policy.to_json(),
            **fitted,
        }

    @classmethod
    def from_json(cls, d: dict) -> PPOConfig:
        d = dict(d)
        d["scenes"] = tuple(d.get("scenes", ()))
        d["policy"] = policy_lib.PolicyConfig.from_json(d["policy"])
        values = d.get("human_values", {})
        if not isinstance(values, dict):
            raise ValueError(f"human_values: expected a table of fields, got {values!r}")
        d["human_values"] = tuple(sorted(values.items()))
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"unknown setting(s) {', '.join(unknown)}")
        return cls(**d)


# What an update holds, measured with ``socialnav policy train --updates 1`` (peak resident): the 14
# seed scenes at 64 x 64, 64 x 512 and 256 x 64 episodes x steps 2.01, 4.11 and 3.01 GB, the 14
# recorded scenes (up to 64 people) at 64 x 64 and 64 x 256 2.89 and 3.93 GB: 5.2-6.0 kB a
# transition (the rollout's buffers, the minibatches, the env states) over about 2 GB of programs;
# 2,000 x 64 on the seed scenes 11.48 GB, 64 x 64 and 64 x 256 with the GSCL channel 2.26 and 3.39 GB.
BYTES_PER_TRANSITION = 6.5e3
BASE_BYTES = 2.5e9


def transitions_per_update(n_scenes: int, config: PPOConfig) -> int:
    """The transitions one update collects: every scene's episodes times the rollout's steps."""
    return n_scenes * config.envs_per_scene * config.rollout_steps


def memory_bytes(n_scenes: int, config: PPOConfig) -> float:
    """What training holds at once (an upper estimate from the measurements above)."""
    return BASE_BYTES + BYTES_PER_TRANSITION * transitions_per_update(n_scenes, config)


def size_problem(n_scenes: int, config: PPOConfig, available_bytes: int | None) -> str | None:
    """Why an update of this size cannot run on a machine with ``available_bytes`` free (None: it
    can; no memory check where that is not known): its transitions are counted in 32-bit integers,
    and held in memory at once (past 80 % of what is free is refused)."""
    per_update = transitions_per_update(n_scenes, config)
    size = f"envs_per_scene {config.envs_per_scene} (--envs-per-scene), rollout_steps {config.rollout_steps} "
    shape = f"{n_scenes} scene(s) x {config.envs_per_scene:,} episodes x {config.rollout_steps:,} steps"
    if per_update >= 2**31:
        return (
            f"{size}(--rollout-steps): {per_update:,} transitions an update ({shape}), past the 2^31 the trainer counts"
        )
    needed = memory_bytes(n_scenes, config)
    if too_big(needed, available_bytes):
        return (f"{size}(--rollout-steps): about {needed / 1e9:.1f} GB at once ({per_update:,} transitions an update: "
                f"{shape}), this machine has {available_bytes / 1e9:.1f} GB available; fewer episodes or steps, "
                "or fewer scenes")  # fmt: skip
    return None


def reward_params() -> env_lib.RewardParams:
    """The env's reward without its Euclidean progress (the guidance field's replaces it)."""
    return env_lib.RewardParams(progress_weight=0.0)


# The arena's replanning period in steps (``evaluation.arena.ArenaConfig.replan_every_steps``,
# which this layer cannot import): an episode's time limit is rounded up to whole periods as there.
ARENA_PERIOD_STEPS = 10


def scene_env(spec: SceneSpec, human_model: str = "social_force", human_values=()) -> env_lib.Env:
    """The environment of ``spec`` as the arena runs it (the env's default step, the timeout in
    whole replanning periods), its people moved by ``human_model`` with its constants set by
    ``human_values`` (pairs, :attr:`PPOConfig.human_values`), with :func:`reward_params`."""
    steps = env_lib.episode_steps(spec.timeout_s, env_lib.EnvConfig.dt_s, ARENA_PERIOD_STEPS)
    config = env_lib.EnvConfig(max_steps=steps, human_model=human_model)
    return env_lib.make_env(spec, config, reward=reward_params(), human_values=dict(human_values))


@struct.dataclass
class Scene:
    """One scene's fixed inputs: its ``env``, the training ``pool`` of N variants
    (:class:`jaxsim.scenes.wrappers.VariantPool`), their guidance ``fields`` (N, H, W), and the
    GSCL network's weights of the GSCL channel (else None)."""

    env: env_lib.Env
    pool: wrappers.VariantPool
    fields: jax.Array
    gscl_weights: object = None


@struct.dataclass
class Runner:
    """One scene's running episodes (B of them): ``env_state``, the state of :func:`training_env`
    (its extras: the pool index of each one's variant, the episode's return, length, person
    contact and rule so far, leaves (B, ...)), ``observation``, and the social channel's state
    ``social`` (:class:`planners.learning.policy_social.SocialState`, batched)."""

    env_state: env_lib.EnvState
    observation: env_lib.Observation
    social: policy_social.SocialState


@struct.dataclass
class TrainState:
    """Everything an update changes: ``weights``, ``opt_state``, one :class:`Runner` per scene
    (a tuple), ``update`` () int32 (updates done)."""

    weights: object
    opt_state: object
    runners: tuple
    update: jax.Array


@struct.dataclass
class Batch:
    """Transitions (N of them): features (N, F), the sampled normalised action u (N, 2), its
    log-probability, the value, the advantage and the return (N,)."""

    features: jax.Array
    u: jax.Array
    log_prob: jax.Array
    value: jax.Array
    advantage: jax.Array
    target: jax.Array


def make_scene(spec: SceneSpec, config: PPOConfig, gscl_weights=None) -> Scene:
    """``spec``'s env and its training pool with the pool's guidance fields (host side)."""
    env = scene_env(spec, config.human_model, config.human_values)
    pool = sample_variants(
        spec, config.seed, config.pool_per_scene, n_slots=padded_slots(spec.n_people_slots), training=True
    )
    pool = wrappers.VariantPool(jax.tree_util.tree_map(jnp.asarray, pool))
    grid = policy_lib.scene_grid(env)
    t = policy_lib.traversal(env)
    fields = jax.jit(jax.vmap(lambda g: policy_lib.guidance_field(t, g, grid)))(pool.variants.goal_xy)
    return Scene(env=env, pool=pool, fields=fields, gscl_weights=gscl_weights)


def _optimizer(config: PPOConfig):
    return optax.chain(optax.clip_by_global_norm(config.max_grad_norm), optax.adam(config.learning_rate, eps=1e-5))


def training_env(scene: Scene, config: PPOConfig, grid: costmap.GridSpec, rule: dict) -> wrappers.Wrapper:
    """``scene.env`` as the trainer steps it (:mod:`jaxsim.scenes.wrappers`): reset by an index of
    the training pool, its reward shaped by ``config.progress_weight`` per metre gained along the
    variant's guidance field, the scene's ``rule`` (:attr:`jaxsim.scenes.spec.SceneSpec.rule`)
    monitored, and the episode's return, length and person contact kept."""

    def distance_to_go_m(state, fields):  # the episode's own field, read at the robot
        return policy_lib.field_at(policy_lib.PoolField(fields, state.extras["pool_index"]), state.robot.xy, grid)

    pool = wrappers.FromPool(scene.env, scene.pool)
    shaped = wrappers.PotentialShaping(pool, distance_to_go_m, scene.fields, config.progress_weight)
    return wrappers.EpisodeStatistics(wrappers.RuleMonitor.of(shaped, rule))


def _batched(tree, n: int):
    return jax.tree_util.tree_map(lambda a: jnp.broadcast_to(a, (n,) + a.shape), tree)


def _fresh_social(obs, n: int) -> policy_social.SocialState:
    return _batched(policy_social.initial_state(obs.people_xy_m.shape[-2]), n)


def init_runner(scene: Scene, config: PPOConfig, key, rule: dict) -> Runner:
    """``envs_per_scene`` episodes of the scene at time 0 on random pool variants (``rule``: the
    scene's social rule, :attr:`jaxsim.scenes.spec.SceneSpec.rule`)."""
    k_pick, k_reset = jax.random.split(key)
    index = scene.pool.draw(k_pick, config.envs_per_scene)
    env = training_env(scene, config, policy_lib.scene_grid(scene.env), rule)
    state, ts = jax.vmap(env.reset)(jax.random.split(k_reset, index.shape[0]), index)
    return Runner(state, ts.observation, _fresh_social(ts.observation, config.envs_per_scene))


@struct.dataclass
class SamplerParams:
    """The training actor's params (one scene): the network's ``weights``, the pool's guidance
    ``fields`` (N, H, W), the base's limits ``robot``, the map's ``occupancy`` (H, W) (the GSCL
    network's walls) and the GSCL network's ``gscl_weights`` (None without that channel)."""

    weights: object
    fields: jax.Array
    robot: robot_lib.RobotParams
    occupancy: jax.Array
    gscl_weights: object = None


@struct.dataclass
class SamplerState:
    """The training actor's state: ``social`` the social channel's state of the B episodes
    (:class:`planners.learning.policy_social.SocialState`, leaves (B, ...)) and ``steps`` () int32,
    the steps taken in this rollout (the GSCL window is refreshed on its steps 0, k, 2k, ...)."""

    social: policy_social.SocialState
    steps: jax.Array


@struct.dataclass
class PoolObservation:
    """What the training actor sees of B episodes: the env's ``observation`` (leaves (B, ...))
    and ``pool_index`` (B,), the pool variant each episode runs (its guidance field)."""

    observation: env_lib.Observation
    pool_index: jax.Array


@struct.dataclass
class Sampled:
    """The training actor's action on B episodes: ``command`` (B, 2) the base's ``(v, omega)``,
    and what PPO keeps of it: the ``features`` (B, F), the sampled normalised action ``u`` (B, 2),
    its ``log_prob`` and the critic's ``value`` (B,)."""

    command: jax.Array
    features: jax.Array
    u: jax.Array
    log_prob: jax.Array
    value: jax.Array


@struct.dataclass
class BatchStep:
    """One step of the trainer's batch (:func:`batch_step`): ``observation`` (the episodes that
    ended already restarted), the step's ``reward`` and ``done`` (B,) (of the episodes as they
    ended, before the restart), and ``ended``: the episodes that ended at this step, summed
    (count, return, reached, touched a person, length in steps, socially successful)."""

    observation: PoolObservation
    reward: jax.Array
    done: jax.Array
    ended: tuple


@struct.dataclass
class BatchWorld:
    """The trainer's B episodes of one scene as one world: ``env_state`` (leaves (B, ...)) and
    ``steps`` () int32, the steps taken in this rollout (each step's restart keys by index)."""

    env_state: env_lib.EnvState
    steps: jax.Array


def _started(social, obs: env_lib.Observation):
    """``social`` with the episodes at their first observation (time 0: restarted at the step
    before, or never stepped) set back to the channel's initial state."""
    first = obs.time_s == 0.0
    return pytree.select_rows(first, _fresh_social(obs, first.shape[0]), social)


def sampler_features(config: PPOConfig, grid: costmap.GridSpec, params: SamplerParams, social, pooled: PoolObservation):
    """``(features (B, F), next social state)`` of B episodes (:func:`planners.learning.policy.observe`
    with each episode's own pool field)."""

    def one(o, i, s):
        return policy_lib.observe(config.policy, o, policy_lib.PoolField(params.fields, i), grid, params.robot, s)

    return jax.vmap(one)(pooled.observation, pooled.pool_index, social)


def sampling_actor(config: PPOConfig, graphdef, grid: costmap.GridSpec, gscl_model=None) -> Actor:
    """The policy as the trainer runs it: an :class:`~jaxsim.actor.Actor` on a batch of B
    episodes (:class:`PoolObservation`) with :class:`SamplerParams`, its action :class:`Sampled`
    from the network's Gaussian (exploration), where the benchmark's
    (:func:`planners.learning.policy.policy_actor`) takes the mean on one episode.

    Each step: the episodes at their first observation get a fresh social channel; on every
    ``gscl_every_steps``-th step of the rollout the GSCL channel's network runs for every episode
    at once (``gscl_model.apply(weights, maps)``, its weights ``params.gscl_weights``, traced);
    then the features, the network and a sample. The step's key is split in three, the first
    drawing the action (the other two are the restart's: :func:`batch_step`)."""
    gscl = config.policy.social_layer == "gscl"
    if gscl and gscl_model is None:
        raise ValueError("sampling_actor: the gscl channel needs the trained network (gscl_model)")
    network = gscl_model.apply if gscl else None

    def init(key, pooled: PoolObservation) -> SamplerState:
        del key
        return SamplerState(_fresh_social(pooled.observation, pooled.pool_index.shape[0]), jnp.int32(0))

    def refresh(params: SamplerParams, social, obs, steps):
        if not gscl:
            return social
        predict = lambda maps: network(params.gscl_weights, maps)
        renew = jax.vmap(lambda o, s: policy_social.gscl_refresh(predict, params.occupancy, grid, o, s))
        return jax.lax.cond(steps % config.policy.gscl_every_steps == 0, renew, lambda o, s: s, obs, social)

    def act(params: SamplerParams, state: SamplerState, pooled: PoolObservation, key):
        k_act = jax.random.split(key, 3)[0]
        social = _started(state.social, pooled.observation)
        social = refresh(params, social, pooled.observation, state.steps)
        x, social = sampler_features(config, grid, params, social, pooled)
        mean, log_std, value = policy_net.apply(graphdef, params.weights, x)
        u = policy_net.sample(k_act, mean, log_std)
        log_prob = policy_net.gaussian_log_prob(u, mean, log_std)
        action = Sampled(policy_lib.command(u, params.robot), x, u, log_prob, value)
        return action, SamplerState(social, state.steps + 1)

    return Actor(init=init, act=act, name="ppo_sampler")


def batch_step(env: wrappers.Wrapper, pool: wrappers.VariantPool, keys: jax.Array):
    """``step(world, action) -> (world, BatchStep)`` of a :class:`BatchWorld` (B episodes of
    ``env``, :func:`training_env`) under a :class:`Sampled` action: every episode steps, the
    ended ones are counted, then restart at once on fresh draws of ``pool`` (the others go on).
    ``keys`` (T, ...): the keys of the rollout's T steps, each split in three (the action's, the
    pool draw's, the restart's), as the actor splits its own."""

    def step(world: BatchWorld, action: Sampled):
        state, ts = jax.vmap(env.step)(world.env_state, action.command)
        done, ended = ts.done, state.extras
        social_success = ts.terminated & ended["rule_kept"]
        counts = (
            done.sum(),
            jnp.where(done, ended["episode_return"], 0.0).sum(),
            (done & ts.terminated).sum(),
            (done & ended["episode_person_contact"]).sum(),
            jnp.where(done, ended["episode_steps"], 0).sum(),
            (done & social_success).sum(),
        )
        _, k_pick, k_reset = jax.random.split(keys[world.steps], 3)
        drawn = pool.draw(k_pick, done.shape[0])
        reset_keys = jax.random.split(k_reset, done.shape[0])
        restarted, after = wrappers.reset_where(env, done, reset_keys, drawn, state, ts)
        pooled = PoolObservation(after.observation, restarted.extras["pool_index"])
        return BatchWorld(restarted, world.steps + 1), BatchStep(pooled, ts.reward, done, counts)

    return step


def _summed(counts: tuple) -> tuple:
    """The rollout's totals of :attr:`BatchStep.ended` (T,) each, added step after step."""
    zero = (jnp.int32(0), jnp.float32(0.0), jnp.int32(0), jnp.int32(0), jnp.int32(0), jnp.int32(0))
    add = lambda total, now: (tuple(a + b for a, b in zip(total, now, strict=True)), None)
    return jax.lax.scan(add, zero, counts)[0]


def make_collect(config: PPOConfig, graphdef, grid: costmap.GridSpec, rule: dict, gscl_model=None) -> Callable:
    """``collect(scene, weights, runner, key) -> (runner, batch, stats)``: ``rollout_steps``
    steps of the runner's episodes and their GAE, jitted (one program per scene shape and rule).

    The rollout is the toolkit's one control loop (:func:`jaxsim.control.control_loop`):
    :func:`sampling_actor` drives the batch world of :func:`batch_step`, whose ended episodes
    restart on the scene's training pool. ``stats``: the episodes that ended, ``(count, sum of
    returns, reached, touched a person, sum of lengths, socially successful)``; socially
    successful is the arena's ``social_success``: the goal reached and the scene's ``rule`` kept
    (:mod:`jaxsim.scenes.rule_monitor`). ``gscl_model``: the GSCL channel's network
    (``gscl_model.apply(weights, maps)``, its weights ``scene.gscl_weights``, traced), run for
    every episode at once on the rollout's steps ``0, k, 2k, ...`` (``k = gscl_every_steps``)."""
    actor = sampling_actor(config, graphdef, grid, gscl_model)  # refuses the gscl channel without its network

    def keep(pooled, action: Sampled, actor_state, step: BatchStep):
        return action.features, action.u, action.log_prob, action.value, step.reward, step.done, step.ended

    def collect(scene: Scene, weights, runner: Runner, key):
        env = training_env(scene, config, grid, rule)
        occupancy = jnp.asarray(scene.env.occupancy.values, jnp.float32)
        params = SamplerParams(weights, scene.fields, scene.env.robot, occupancy, scene.gscl_weights)
        keys = jax.random.split(key, config.rollout_steps)
        pooled = PoolObservation(runner.observation, runner.env_state.extras["pool_index"])
        start = BatchWorld(runner.env_state, jnp.int32(0))
        (world, pooled, sampler), (x, u, log_prob, value, reward, done, counts) = control_loop(
            batch_step(env, scene.pool, keys), actor, params, start, pooled,
            SamplerState(runner.social, jnp.int32(0)), keys, record=keep,
        )  # fmt: skip
        social = _started(sampler.social, pooled.observation)
        last_x, _ = sampler_features(config, grid, params, social, pooled)
        _, _, last_value = policy_net.apply(graphdef, weights, last_x)
        advantage = gae(value, reward, done, last_value, config.gamma, config.gae_lambda)
        flat = lambda a: a.reshape((-1,) + a.shape[2:])
        batch = Batch(flat(x), flat(u), flat(log_prob), flat(value), flat(advantage), flat(advantage + value))
        return Runner(world.env_state, pooled.observation, social), batch, _summed(counts)

    return jax.jit(collect)


def gae(values, rewards, dones, last_value, gamma: float, lam: float):
    """(T, B) generalised advantage estimates (Schulman et al. 2016) of T steps of B episodes;
    ``dones[t]``: the episode ended at step t (its successor is another episode's start)."""

    def step(carry, t):
        advantage_next, value_next = carry
        value, reward, done = t
        not_done = 1.0 - done.astype(jnp.float32)
        delta = reward + gamma * value_next * not_done - value
        advantage = delta + gamma * lam * not_done * advantage_next
        return (advantage, value), advantage

    _, advantages = jax.lax.scan(step, (jnp.zeros_like(last_value), last_value), (values, rewards, dones), reverse=True)
    return advantages


def make_update(config: PPOConfig, graphdef) -> Callable:
    """``update(weights, opt_state, batch, key) -> (weights, opt_state, losses)``: ``epochs``
    passes of ``minibatches`` shuffled minibatches, jitted. ``losses``: the last pass's mean
    (policy, value, entropy, approximate KL)."""
    optimizer = _optimizer(config)

    def loss_fn(weights, b: Batch):
        mean, log_std, value = policy_net.apply(graphdef, weights, b.features)
        log_prob = policy_net.gaussian_log_prob(b.u, mean, log_std)
        ratio = jnp.exp(log_prob - b.log_prob)
        adv = (b.advantage - b.advantage.mean()) / (b.advantage.std() + 1e-8)
        clipped = jnp.clip(ratio, 1.0 - config.clip_eps, 1.0 + config.clip_eps)
        policy_loss = -jnp.minimum(ratio * adv, clipped * adv).mean()
        value_clipped = b.value + jnp.clip(value - b.value, -config.clip_eps, config.clip_eps)
        value_loss = 0.5 * jnp.maximum((value - b.target) ** 2, (value_clipped - b.target) ** 2).mean()
        entropy = policy_net.gaussian_entropy(log_std)
        total = policy_loss + config.value_coef * value_loss - config.entropy_coef * entropy
        kl = ((ratio - 1.0) - jnp.log(ratio)).mean()
        return total, jnp.stack([policy_loss, value_loss, entropy, kl])

    grad_fn = jax.grad(loss_fn, has_aux=True)

    def update(weights, opt_state, batch: Batch, key):
        n = batch.u.shape[0]
        size = n // config.minibatches

        def epoch(carry, k):
            perm = jax.random.permutation(k, n)[: size * config.minibatches]
            shaped = jax.tree_util.tree_map(lambda a: a[perm].reshape((config.minibatches, size) + a.shape[1:]), batch)

            def minibatch(carry, b):
                weights, opt_state = carry
                grads, losses = grad_fn(weights, b)
                updates, opt_state = optimizer.update(grads, opt_state, weights)
                return (optax.apply_updates(weights, updates), opt_state), losses

            return jax.lax.scan(minibatch, carry, shaped)

        (weights, opt_state), losses = jax.lax.scan(epoch, (weights, opt_state), jax.random.split(key, config.epochs))
        return weights, opt_state, losses[-1].mean(axis=0)

    return jax.jit(update)


class Trainer:
    """PPO over ``specs`` with ``config``: :meth:`initial_state`, then :meth:`step` per update.

    Host-side bookkeeping only; the work is in the jitted collectors (one per scene) and the
    update. ``graphdef`` is the network's static structure. The GSCL channel's network is
    loaded from ``config.policy.gscl_run`` (``ValueError`` naming the folder if it is not a run).
    """

    def __init__(self, specs: Sequence[SceneSpec], config: PPOConfig):
        if not specs:
            raise ValueError("PPO needs at least one scene")
        self.config = config
        self.specs = list(specs)
        self.gscl_model = None
        if config.policy.social_layer == "gscl":
            self.gscl_model = policy_social.load_gscl(config.policy.gscl_run)
        gscl_weights = None if self.gscl_model is None else self.gscl_model.weights
        self.scenes = [make_scene(s, config, gscl_weights) for s in self.specs]
        window = self.scenes[0].env.config.window_cells
        self.n_features = config.policy.n_features(window)
        self.graphdef, self._weights0 = policy_net.init_weights(
            self.n_features, config.policy.hidden, config.seed, config.policy.initial_log_std
        )
        self.grids = [policy_lib.scene_grid(s.env) for s in self.scenes]
        self._collect = [
            make_collect(config, self.graphdef, g, spec.rule, self.gscl_model)
            for g, spec in zip(self.grids, self.specs, strict=True)
        ]
        self._update = make_update(config, self.graphdef)
        self.transitions_per_update = len(self.scenes) * config.envs_per_scene * config.rollout_steps

    def _key(self, update: int, *path: int):
        key = jax.random.fold_in(jax.random.PRNGKey(self.config.seed), update)
        for p in path:
            key = jax.random.fold_in(key, p)
        return key

    def initial_state(self) -> TrainState:
        start = jax.random.fold_in(jax.random.PRNGKey(self.config.seed), 2**31 - 1)  # no update's key
        runners = tuple(
            init_runner(scene, self.config, jax.random.fold_in(start, k), spec.rule)
            for k, (scene, spec) in enumerate(zip(self.scenes, self.specs, strict=True))
        )
        opt_state = _optimizer(self.config).init(self._weights0)
        return TrainState(self._weights0, opt_state, runners, jnp.int32(0))

    def step(self, state: TrainState) -> tuple[TrainState, dict]:
        """One update: ``(new state, metrics)``; metrics are host floats (episodes ended in this
        update's rollouts, their mean return, goal, person-contact and social success rates, the
        losses)."""
        u = int(state.update)
        runners, batches, stats = [], [], []
        for k, (scene, collect) in enumerate(zip(self.scenes, self._collect, strict=True)):
            runner, batch, scene_stats = collect(scene, state.weights, state.runners[k], self._key(u, 0, k))
            runners.append(runner)
            batches.append(batch)
            stats.append(scene_stats)
        batch = jax.tree_util.tree_map(lambda *a: jnp.concatenate(a), *batches)
        weights, opt_state, losses = self._update(state.weights, state.opt_state, batch, self._key(u, 1))
        # Read back once everything is dispatched (a float() per scene would wait on each collector).
        totals = np.zeros(6)
        for scene_stats in stats:
            totals += np.array([float(s) for s in scene_stats])
        ended = totals[0]
        dt_s = self.scenes[0].env.config.dt_s
        metrics = {
            "update": u + 1,
            "env_steps": (u + 1) * self.transitions_per_update,
            "episodes": int(ended),
            "return": float(totals[1] / ended) if ended else float("nan"),
            "goal_rate": float(totals[2] / ended) if ended else float("nan"),
            "contact_rate": float(totals[3] / ended) if ended else float("nan"),
            "social_rate": float(totals[5] / ended) if ended else float("nan"),
            "episode_s": float(totals[4] / ended * dt_s) if ended else float("nan"),
            "policy_loss": float(losses[0]),
            "value_loss": float(losses[1]),
            "entropy": float(losses[2]),
            "approx_kl": float(losses[3]),
        }
        return TrainState(weights, opt_state, tuple(runners), jnp.int32(u + 1)), metrics


def _episode_return(env, actor, params, index, key):
    from socialnav.jaxsim.scenes.actor import rollout

    return jnp.sum(rollout(env, actor, params, index, key)[1].reward)


# The episodes of a batch of pool indices and keys, one program per env structure and actor.
_episode_returns = jax.jit(jax.vmap(_episode_return, in_axes=(None, None, None, 0, 0)), static_argnums=1)


def evaluate_return(trainer: Trainer, weights, n_variants: int = 16, seed: int = 7) -> float:
    """Mean return of the deterministic (mean-action) policy over ``n_variants`` training-pool
    variants of each scene, one episode each (the training's reward: :func:`training_env`)."""
    config = trainer.config
    totals = []
    for scene, grid, spec in zip(trainer.scenes, trainer.grids, trainer.specs, strict=True):
        actor = policy_lib.policy_actor(config.policy, trainer.graphdef, grid, gscl_model=trainer.gscl_model)
        params = policy_lib.policy_params(scene.env, weights, trainer.gscl_model)
        env = training_env(scene, config, grid, spec.rule)
        index = jnp.arange(n_variants) % config.pool_per_scene
        keys = jax.random.split(jax.random.PRNGKey(seed), n_variants)
        totals.append(np.asarray(_episode_returns(env, actor, params, index, keys)))
    return float(np.mean(np.concatenate(totals)))


__all__ = [
    "Batch",
    "BatchStep",
    "BatchWorld",
    "PPOConfig",
    "PoolObservation",
    "Runner",
    "Sampled",
    "SamplerParams",
    "SamplerState",
    "Scene",
    "TrainState",
    "Trainer",
    "batch_step",
    "evaluate_return",
    "gae",
    "make_collect",
    "make_update",
    "reward_params",
    "sampler_features",
    "sampling_actor",
    "scene_env",
    "training_env",
]
