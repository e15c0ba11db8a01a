"""socialnav: the composition root of the toolkit.

The ``socialnav`` command is :mod:`socialnav.cli`, one module a subcommand beside its entry point
(:mod:`socialnav.cli.arena`, :mod:`socialnav.cli.gscl`, ...; the pipelines that join parts,
``socialnav run`` and ``ablation``, in :mod:`socialnav.cli.pipelines`; shared argument types in
:mod:`socialnav.cli.argtypes`). Beside it, what the commands share: the runtime set-up
(:mod:`socialnav.runtime`), batch jobs in shards, locally or on Ray (:mod:`socialnav.backend`;
the jobs' shards: :mod:`socialnav.simulate_shards`, :mod:`socialnav.gscl_shards`,
:mod:`socialnav.evaluate_shards`),
run-folder locks (:mod:`socialnav.locking`), and the studies that join parts which do not import
each other: the causal pipeline refereed by the simulator (:mod:`socialnav.referee_study`) and
the ablation's simulated series (:mod:`socialnav.ablation_study`). It may import every part; no
part imports it.
"""

from socialnav.common import __version__

__all__ = ["__version__"]
