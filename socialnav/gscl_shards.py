"""``socialnav gscl generate`` cut into shards of samples (``--shard-samples``, ``--backend ray``).

A shard is samples ``start .. stop - 1`` of one family (:func:`models.dataset.generate_range`,
aligned to the generator's chunks, so the same bits as one call); the driver saves each beside
the dataset (``.<name>.npz.shards/``) as it arrives and joins them when all are there. A killed
driver leaves the finished shards; a rerun with the same settings computes only the missing ones.
"""

from __future__ import annotations

import pathlib

from socialnav import backend as backend_lib


def staging(out: pathlib.Path) -> pathlib.Path:
    """Where the shards of the dataset ``out`` are kept until it is written."""
    return out.with_name(f".{out.name}.shards")


def generate_shard(seed: int, name: str, start: int, stop: int):
    """Samples ``start .. stop - 1`` of one family (here or in a Ray worker)."""
    from socialnav.models import dataset

    return dataset.generate_range(seed, name, start, stop)


def _save_shard(shard, result) -> None:
    import numpy as np

    from socialnav.common.atomic import write_bytes_atomic

    x, y = result
    write_bytes_atomic(shard.output, lambda handle: np.savez(handle, inputs=x, targets=y))


def generate_sharded(args, counts: dict[str, int]):
    """The dataset cut into shards of samples of one family (aligned to the generator's 1024-sample
    chunks, so the same bits as one call), run by the chosen backend, kept beside ``--out`` until
    the dataset is written; a rerun with the same settings computes only the missing ones."""

    import numpy as np

    from socialnav.models import dataset

    chunk = dataset.CHUNK
    size = max(chunk, -(-(args.shard_samples or max(counts.values(), default=chunk)) // chunk) * chunk)
    folder = staging(args.out)
    layout = {"seed": args.seed, "counts": counts, "shard_samples": size}
    backend_lib.staging_folder(folder, layout)
    names = [f for f in dataset.FAMILIES if counts.get(f, 0) > 0]
    shards = [
        backend_lib.Shard(
            name=f"{name}[{start}:{min(start + size, counts[name])}]",
            output=folder / f"{k:02d}-{name}-{start:07d}.npz",
            args=(args.seed, name, start, min(start + size, counts[name])),
            work=min(start + size, counts[name]) - start,
        )
        for k, name in enumerate(names)
        for start in range(0, counts[name], size)
    ]
    backend_lib.run_with_args(generate_shard, _save_shard, shards, args, desc="gscl generate", unit="samples")
    inputs, targets, family = [], [], []
    for shard in shards:
        with np.load(shard.output) as part:
            inputs.append(part["inputs"])
            targets.append(part["targets"])
        family.append(np.full(len(inputs[-1]), names.index(shard.args[1]), np.int8))
    return dataset.assemble(names, inputs, targets, family)
