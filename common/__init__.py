"""socialnav.common: the leaf every part may import, importing no part itself.

One home each for what several parts need and none owns: atomic file writes
(:mod:`~socialnav.common.atomic`), progress reporting (:mod:`~socialnav.common.progress`), pytree helpers
(:mod:`~socialnav.common.pytree`), JSON read as people write it (:mod:`~socialnav.common.strict_json`: a key
given twice is an error) and the simulator log's file contract (:mod:`~socialnav.common.logschema`), which
the simulator writes and the causal pipeline reads without importing each other.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("socialnav-jax")
except PackageNotFoundError:  # pragma: no cover - running from a source tree that is not installed
    __version__ = "0+unknown"

from socialnav.common.atomic import write_atomic, write_bytes_atomic, write_text_atomic

__all__ = ["__version__", "write_atomic", "write_bytes_atomic", "write_text_atomic"]
