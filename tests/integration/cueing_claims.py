"""What "beats", "comparable" and "misses" mean when two cueings are compared by their scores.

A score (a false-cue share, a perceived roll or pitch RMS error) moves by a few per cent
with the last digits of the arithmetic: the MPC's warm-started ADMM stops at its iteration
budget, so a CPU's BLAS kernels or a solver's release change its plan slightly. Across five
OpenBLAS kernel sets (``OPENBLAS_CORETYPE``) the ratio of two scores moves by up to 9 % on
the thinnest case. A claim is therefore stated with a margin:

- ours *beats* theirs: at most :data:`BEATS` times theirs;
- ours is *comparable* to theirs: at most :data:`COMPARABLE` times theirs;
- ours *misses* theirs: at least :data:`MISSES` times theirs.
"""

BEATS = 0.97
COMPARABLE = 1.05
MISSES = 1.02

__all__ = ["BEATS", "COMPARABLE", "MISSES", "beats", "comparable", "misses"]


def beats(ours: float, theirs: float) -> bool:
    """Whether ``ours`` is lower than ``theirs`` by the margin (a lower score is better)."""
    return ours <= BEATS * theirs


def comparable(ours: float, theirs: float) -> bool:
    """Whether ``ours`` is no more than a few per cent above ``theirs``."""
    return ours <= COMPARABLE * theirs


def misses(ours: float, theirs: float) -> bool:
    """Whether ``ours`` is higher than ``theirs`` by the margin."""
    return ours >= MISSES * theirs
