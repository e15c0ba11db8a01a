"""socialnav: the composition root of the toolkit.

The ``socialnav`` command is :mod:`socialnav.cli`, one module a subcommand beside its entry point
(:mod:`socialnav.cli.arena`, :mod:`socialnav.cli.gscl`, ...; the pipelines that join parts,
``socialnav run`` and ``ablation``, in :mod:`socialnav.cli.pipelines`; shared argument types in
:mod:`socialnav.cli.argtypes`). Beside it, what the commands share: the runtime set-up
(:mod:`socialnav.runtime`), batch jobs in shards, locally or on Ray (:mod:`socialnav.backend`)
and run-folder locks (:mod:`socialnav.locking`). It may import every part; no part imports it.
"""

from socialnav.common import __version__

__all__ = ["__version__"]
