"""GSCL's U-Net (seed 002 Sec. 4.2) in Flax NNX: input map (40 x 40 pixel codes) -> cost map.

The paper's structure: three encoder blocks of two 3x3 convolutions (padding 1) with batch norm
and ReLU, each followed by 2x2 max-pooling; a bottleneck block; three decoder stages of a 2x2
stride-2 transposed convolution, concatenation with the encoder's skip, and a block of two 3x3
convolutions with batch norm and ReLU; a 1x1 convolution to one output channel.

This project's choices (the paper does not give them):

* **Input encoding.** The paper feeds the pixel-code image. The network here turns it into one
  binary channel per non-free code (wall, person, heading, goal): the codes are categories, and
  a scalar 0/25/100/200/255 would tell the first convolution that a heading pixel is "a quarter
  of a person". Optionally (``coords``, on by default) two channels with the cell's x and y in
  [-1, 1]: the robot always sits at the centre, and rules such as "keep right of the way to the
  goal" are about where things are relative to it.
* **Output.** A sigmoid, so costs stay in [0, 1] like the normalised targets; its bias starts
  at -3 (a cost of 0.05), near the average target.
* **A forbidden head** (``forbidden_head``, on for the runs trained on today's targets): a second
  output channel, the logit of "this cell is forbidden" (the queue's U,
  :data:`models.social_costs.FORBIDDEN`), trained as a classification beside the graded costs'
  regression, as Nav2 keeps a keepout mask apart from its graded layers. The call returns one
  map: :data:`models.social_costs.FORBIDDEN` where the probability is at least 1/2, else the
  graded channel scaled to ``[0, GRADED_TOP]``, so that a cost reader needs no second output.
  Why not one regressed channel with a forbidden level above the graded ones (tried): the
  least-squares answer where the network is unsure is the mean, and along the
  line's tail it stayed below the lethal threshold, so plans crossed the line's side.
  With ``forbidden_features`` the head is a **separate branch** (:data:`BRANCH`): a second U-Net
  of its own widths whose one output is the forbidden logit, the main network keeping its one graded
  output. Training can then keep the main network as a source model drew it
  (:attr:`models.config.TrainConfig.freeze_graded`): a shared trunk fine-tuned to learn the U
  drew other costs weaker (the blind corner beside a queue).
* **Width.** ``features = (f1, f2, f3, bottleneck)``. :data:`PAPER_FEATURES` (32, 64, 128, 256)
  has about 1.9 M parameters, near the paper's ~1.6 M; the default for CPU training is
  :data:`CPU_FEATURES` (see the README's measurements for what it costs and buys).

Linen would do the same; NNX is used because the Flax docs recommend it for new code. Training
and inference go through :func:`nnx.split` / :func:`nnx.merge` and plain ``jax.jit`` so that the
jitted functions see pure pytrees (no per-call graph traversal).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from socialnav.models import grid
from socialnav.models.social_costs import FORBIDDEN, GRADED_TOP

PAPER_FEATURES = (32, 64, 128, 256)
CPU_FEATURES = (16, 32, 64, 128)
INPUT_CHANNEL_CODES = (grid.WALL, grid.PERSON, grid.HEADING, grid.GOAL)
HEAD_BIAS = -3.0
BRANCH = "forbidden_branch"  # the attribute holding the separate forbidden branch


def encode_input(maps, coords: bool = True):
    """(B, 40, 40) pixel-code maps (any int or float dtype) -> (B, 40, 40, C) float32 channels.

    One binary channel per code in :data:`INPUT_CHANNEL_CODES`, plus x and y in [-1, 1] when
    ``coords``.
    """
    maps = jnp.asarray(maps)
    channels = [(maps == code).astype(jnp.float32) for code in INPUT_CHANNEL_CODES]
    if coords:
        ramp = jnp.linspace(-1.0, 1.0, grid.GRID, dtype=jnp.float32)
        shape = maps.shape
        channels.append(jnp.broadcast_to(ramp[None, None, :], shape))  # x, right
        channels.append(jnp.broadcast_to(-ramp[None, :, None], shape))  # y, up
    return jnp.stack(channels, axis=-1)


class UpConv(nnx.ConvTranspose):
    """The decoder's 2x2, stride-2 transposed convolution, computed as one product: every input
    pixel becomes a 2 x 2 block of outputs, ``y[2i + u, 2j + v] = x[i, j] @ K[1 - u, 1 - v] + b``
    (``nnx.ConvTranspose`` flips the kernel). The same parameters as ``nnx.ConvTranspose(in, out,
    (2, 2), strides=(2, 2))``, so every checkpoint loads as before, and its outputs to float
    rounding (tested). Why: XLA's CPU backend ran the transposed convolution as a convolution of
    the zero-dilated input, 18 % of a training step (``benchmarks/profile_gscl_step.py``); as a
    product the default model's training loop is faster on both instruction sets
    (``benchmarks/bench_gscl_loop.py`` against ``--transposed-conv``, batch 32, 2 cores,
    interleaved processes: AVX-512 166-175 -> 230-253 samples/s; AVX2 emulated 173-197
    -> 224-259)."""

    def __init__(self, in_features: int, out_features: int, *, use_bias: bool = True, rngs: nnx.Rngs):
        super().__init__(in_features, out_features, (2, 2), strides=(2, 2), use_bias=use_bias, rngs=rngs)

    def __call__(self, x):
        z = jnp.einsum("...ijc,uvco->...iujvo", x, self.kernel[...][::-1, ::-1])
        *lead, h, _, w, _, out = z.shape
        y = z.reshape(*lead, 2 * h, 2 * w, out)
        return y + self.bias[...] if self.use_bias else y


class ConvBlock(nnx.Module):
    """Two (3x3 conv, batch norm, ReLU) layers."""

    def __init__(self, in_features: int, out_features: int, *, rngs: nnx.Rngs):
        self.conv1 = nnx.Conv(in_features, out_features, (3, 3), padding=1, use_bias=False, rngs=rngs)
        self.norm1 = nnx.BatchNorm(out_features, momentum=0.9, rngs=rngs)
        self.conv2 = nnx.Conv(out_features, out_features, (3, 3), padding=1, use_bias=False, rngs=rngs)
        self.norm2 = nnx.BatchNorm(out_features, momentum=0.9, rngs=rngs)

    def __call__(self, x):
        x = nnx.relu(self.norm1(self.conv1(x)))
        return nnx.relu(self.norm2(self.conv2(x)))


class UNet(nnx.Module):
    """The GSCL U-Net. Call on (B, 40, 40) pixel-code maps; returns (B, 40, 40) costs in [0, 1].

    Args:
      features: channels of the three encoder blocks and the bottleneck.
      coords: add the two coordinate channels to the input (see the module docstring).
      forbidden_head: add the forbidden channel (see the module docstring); the call then returns
        graded costs in ``[0, GRADED_TOP]`` and ``FORBIDDEN`` where the head says forbidden.
      forbidden_features: None (the default): the forbidden channel is a second output of the
        last layer; four widths: it is the one output of a separate U-Net of these widths (the
        attribute ``forbidden_branch``). Needs ``forbidden_head``.
    """

    def __init__(
        self,
        features=CPU_FEATURES,
        coords: bool = True,
        forbidden_head: bool = False,
        forbidden_features=None,
        *,
        rngs: nnx.Rngs,
    ):
        if len(features) != 4 or any(int(f) < 1 for f in features):
            raise ValueError(f"features must be 4 positive widths (3 encoder blocks, bottleneck), got {features}")
        self.features = tuple(int(f) for f in features)
        self.coords = coords
        self.forbidden_head = bool(forbidden_head)
        if forbidden_features is not None and not self.forbidden_head:
            raise ValueError("forbidden_features needs forbidden_head")
        f1, f2, f3, fb = self.features
        in_ch = len(INPUT_CHANNEL_CODES) + (2 if coords else 0)
        self.enc = nnx.List([ConvBlock(i, o, rngs=rngs) for i, o in ((in_ch, f1), (f1, f2), (f2, f3))])
        self.bottleneck = ConvBlock(f3, fb, rngs=rngs)
        self.up = nnx.List([UpConv(i, o, rngs=rngs) for i, o in ((fb, f3), (f3, f2), (f2, f1))])
        self.dec = nnx.List([ConvBlock(2 * o, o, rngs=rngs) for o in (f3, f2, f1)])
        # Output bias at the logit of a typical cost (sigmoid(-3) = 0.05): most pixels cost nothing,
        # and starting from 0.5 everywhere spends the first hundreds of steps unlearning that.
        outputs = 2 if self.forbidden_head and forbidden_features is None else 1
        self.head = nnx.Conv(f1, outputs, (1, 1), bias_init=nnx.initializers.constant(HEAD_BIAS), rngs=rngs)
        self.forbidden_branch = (
            None if forbidden_features is None else UNet(forbidden_features, coords, False, rngs=rngs)
        )

    def heads(self, maps):
        """``(graded, forbidden_logit)``: (B, 40, 40) graded costs in [0, 1] (the sigmoid of the
        first channel) and the forbidden channel's logits, or None without the forbidden head."""
        out = self.logits(maps)
        if self.forbidden_branch is not None:
            return nnx.sigmoid(out[..., 0]), self.forbidden_branch.logits(maps)[..., 0]
        return nnx.sigmoid(out[..., 0]), (out[..., 1] if self.forbidden_head else None)

    def logits(self, maps):
        """(B, 40, 40, outputs) raw outputs of the main network's last layer."""
        x = encode_input(maps, self.coords)
        skips = []
        for block in self.enc:
            x = block(x)
            skips.append(x)
            x = nnx.max_pool(x, (2, 2), strides=(2, 2))
        x = self.bottleneck(x)
        for up, block, skip in zip(self.up, self.dec, reversed(skips)):
            x = block(jnp.concatenate([up(x), skip], axis=-1))
        return self.head(x)

    def __call__(self, maps):
        graded, forbidden_logit = self.heads(maps)
        if forbidden_logit is None:
            return graded
        return combine_heads(graded, forbidden_logit)


def combine_heads(graded, forbidden_logit):
    """One cost map from the two channels: ``FORBIDDEN`` where the forbidden probability is at
    least 1/2 (logit >= 0), else ``GRADED_TOP x graded``."""
    return jnp.where(forbidden_logit >= 0.0, FORBIDDEN, GRADED_TOP * graded)


def parameter_count(model: nnx.Module) -> int:
    """Number of trainable parameters (batch-norm statistics excluded)."""
    return int(sum(np.prod(p.shape) for p in jax.tree.leaves(nnx.state(model, nnx.Param))))
