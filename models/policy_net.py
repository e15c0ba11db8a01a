"""The learned policy's network: an actor-critic MLP over a feature vector (Flax nnx).

The actor head gives the mean of a diagonal Gaussian over a normalised action ``u`` (2,) and a
state-independent log standard deviation (PPO's usual parameterisation for continuous control,
Schulman et al. 2017; purejaxrl's and CleanRL's ``ppo_continuous``); the critic a value. Actor
and critic are separate MLPs with tanh activations and orthogonal initialisation (the actor's
last layer scaled by 0.01, the critic's by 1: the "37 implementation details of PPO", Huang et
al. 2022). The features and what ``u`` means to the robot are the actor's business
(:mod:`planners.learning.policy`); this module knows only vectors.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
from flax import nnx


class _MLP(nnx.Module):
    def __init__(self, sizes: tuple[int, ...], last_scale: float, *, rngs: nnx.Rngs):
        layers = []
        for k, (a, b) in enumerate(zip(sizes[:-1], sizes[1:], strict=True)):
            scale = last_scale if k == len(sizes) - 2 else math.sqrt(2.0)
            init = nnx.initializers.orthogonal(scale)
            layers.append(nnx.Linear(a, b, kernel_init=init, bias_init=nnx.initializers.zeros, rngs=rngs))
        self.layers = nnx.List(layers)

    def __call__(self, x):
        for k, layer in enumerate(self.layers):
            x = layer(x)
            if k < len(self.layers) - 1:
                x = jnp.tanh(x)
        return x


class ActorCritic(nnx.Module):
    """``(features (..., F)) -> (mean (..., A), log_std (A,), value (...))``.

    Args:
      n_features: F; n_actions: A; hidden: the hidden layers' widths (both MLPs);
      initial_log_std: the exploration noise's log standard deviation at the start.
    """

    def __init__(
        self,
        n_features: int,
        n_actions: int = 2,
        hidden: tuple[int, ...] = (128, 128),
        initial_log_std: float = -0.5,
        *,
        rngs: nnx.Rngs,
    ):
        self.actor = _MLP((n_features, *hidden, n_actions), 0.01, rngs=rngs)
        self.critic = _MLP((n_features, *hidden, 1), 1.0, rngs=rngs)
        self.log_std = nnx.Param(jnp.full((n_actions,), initial_log_std, jnp.float32))

    def __call__(self, features):
        return self.actor(features), self.log_std[...], self.critic(features)[..., 0]


def init_weights(n_features: int, hidden: tuple[int, ...], seed: int, initial_log_std: float = -0.5):
    """``(graphdef, weights)`` of a fresh :class:`ActorCritic` (``nnx.split``: the graphdef is
    static, the weights a pytree of arrays that can be traced, saved and swapped)."""
    model = ActorCritic(n_features, 2, tuple(hidden), initial_log_std, rngs=nnx.Rngs(seed))
    return nnx.split(model)


def apply(graphdef, weights, features):
    """The network of ``weights`` on ``features`` (..., F): ``(mean, log_std, value)``."""
    return nnx.merge(graphdef, weights)(features)


def gaussian_log_prob(x, mean, log_std):
    """(...) log density of ``x`` (..., A) under the diagonal Gaussian."""
    z = (x - mean) * jnp.exp(-log_std)
    return jnp.sum(-0.5 * z**2 - log_std - 0.5 * math.log(2 * math.pi), axis=-1)


def gaussian_entropy(log_std):
    """() entropy of the diagonal Gaussian (its mean does not matter)."""
    return jnp.sum(log_std + 0.5 * math.log(2 * math.pi * math.e))


def sample(key, mean, log_std):
    """A draw (..., A) from the diagonal Gaussian."""
    return mean + jnp.exp(log_std) * jax.random.normal(key, mean.shape, mean.dtype)
