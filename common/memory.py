"""How much memory this machine has free: for the estimates a job checks before allocating."""

from __future__ import annotations


def available_bytes() -> int | None:
    """``MemAvailable`` of ``/proc/meminfo`` in bytes (what can be allocated without swapping),
    or None where that file does not exist (no check is made there)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


# The share of the available memory a job may plan to take at once: the rest is left to the
# estimate's error, the libraries' own buffers and whatever else the machine runs.
USABLE_SHARE = 0.8


def too_big(needed_bytes: float, available: float | None, share: float = USABLE_SHARE) -> bool:
    """Whether ``needed_bytes`` at once is more than ``share`` of ``available`` bytes (False where
    ``available`` is None: not known, no check)."""
    return available is not None and needed_bytes > share * available


def shortfall(needed_bytes: float, share: float = USABLE_SHARE) -> int | None:
    """The bytes available where a job needing ``needed_bytes`` at once would take more than
    ``share`` of them (it does not fit: the caller refuses it, naming both); None where it fits, or
    where the available memory is not known."""
    available = available_bytes()
    return available if too_big(needed_bytes, available, share) else None


def units_that_fit(
    available_bytes: float, base_bytes: float, bytes_per_unit: float, share: float = USABLE_SHARE
) -> int:
    """How many units of ``bytes_per_unit`` fit beside ``base_bytes`` in ``share`` of
    ``available_bytes`` (what a refusal by :func:`shortfall` names as the most that would run)."""
    return max(0, int((share * available_bytes - base_bytes) // bytes_per_unit))
