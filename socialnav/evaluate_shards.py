"""``socialnav evaluate`` cut into shards of replicas (``--shard-replicas``, ``--backend ray``).

Shard ``k`` runs replicas ``first .. first + n - 1`` of seed 000's protocol
(:func:`evaluation.warehouse.run_evaluation` with ``first_replica``: the same replicas as one run
of them all) and returns its result without the routes; the driver saves each under
``<out>/.shards/`` as it arrives, and when every shard is there merges them
(:func:`evaluation.warehouse.merge`) and rebuilds the routes. A killed driver leaves the finished
shards; a rerun with the same settings computes only the missing ones.
"""

from __future__ import annotations

import pathlib

from socialnav import backend as backend_lib
from socialnav.evaluation import warehouse
from socialnav.evaluation.protocol import ProtocolConfig
from socialnav.jaxsim.scenario import WAREHOUSE_DIR, load_scenario
from socialnav.planners.warehouse.tables import CausalTables

STAGING = ".shards"


def compute_shard(scenario_dir, tables_file, first, n, slots, seed, settings) -> warehouse.EvaluationResult:
    """Replicas ``first .. first + n - 1`` of the protocol (here or in a Ray worker); the routes
    (``plans``) stay behind: the driver rebuilds them."""
    import dataclasses

    scenario = load_scenario(scenario_dir or WAREHOUSE_DIR)
    result = warehouse.run_evaluation(
        scenario,
        CausalTables.load(tables_file),
        replicas=n,
        slots=slots,
        seed=seed,
        cfg=ProtocolConfig.for_params(scenario.params, **settings),
        progress=False,
        first_replica=first,
    )
    return dataclasses.replace(result, plans={})


def _save_shard(shard, result) -> None:
    import pickle

    from socialnav.common.atomic import write_bytes_atomic

    write_bytes_atomic(shard.output, lambda handle: pickle.dump(result, handle))


def run_sharded(scenario, tables, tables_file, out, args, slots, settings, size) -> warehouse.EvaluationResult:
    """The replicas cut into shards of ``size``, run by the chosen backend, kept under
    ``<out>/.shards/`` until all are done (a rerun with the same settings computes only the
    missing ones), then merged."""
    import dataclasses
    import pickle

    staging = out / STAGING
    layout = {
        "scenario": None if args.scenario is None else str(args.scenario),
        "tables": str(pathlib.Path(tables_file).resolve()),
        "replicas": args.replicas,
        "shard_replicas": size,
        "slots": slots,
        "seed": args.seed,
        "settings": settings,
    }
    backend_lib.staging_folder(staging, layout)
    scenario_dir = None if args.scenario is None else str(pathlib.Path(args.scenario).resolve())
    shards = [
        backend_lib.Shard(
            name=f"replicas {first}-{first + min(size, args.replicas - first) - 1}",
            output=staging / f"replicas-{first:06d}.pkl",
            args=(scenario_dir, layout["tables"], first, min(size, args.replicas - first), slots, args.seed, settings),
            work=min(size, args.replicas - first),
        )
        for first in range(0, args.replicas, size)
    ]
    backend_lib.run_with_args(compute_shard, _save_shard, shards, args, desc="evaluate", unit="replicas")
    parts = [pickle.loads(s.output.read_bytes()) for s in shards]
    result = warehouse.merge(parts)
    result = dataclasses.replace(
        result,
        plans={name: plan for name, (plan, _) in warehouse.method_plans(scenario, tables).items()},
        config={**result.config, "shard_replicas": size, **backend_lib.describe(args)},
    )
    return result
