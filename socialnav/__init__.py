"""socialnav: the composition root of the toolkit.

The ``socialnav`` command (:mod:`socialnav.cli`) with one subcommand per job, the runtime set-up
(:mod:`socialnav.runtime`), shared argument types (:mod:`socialnav.argtypes`) and the pipelines
that join parts (:mod:`socialnav.pipelines`). It may import every part; no part imports it.
"""

from socialnav.common import __version__

__all__ = ["__version__"]
