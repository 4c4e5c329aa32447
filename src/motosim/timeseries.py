"""Time-first series of named signals: one row per instant, one column per signal."""

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = ["TimeSeries"]


@dataclass(frozen=True, slots=True)
class TimeSeries:
    """Signals sampled at the instants ``t``.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Strictly increasing time [s].
    data : ndarray, shape (n, k)
        Column ``j`` is the signal ``names[j]``, in the unit of :mod:`motosim.signals`.
    names : tuple of str
        Signal names.

    Examples
    --------
    >>> ts = TimeSeries(np.array([0.0, 1.0]), np.array([[1.0], [2.0]]), ("theta_h",))
    >>> ts["theta_h"]
    array([1., 2.])
    """

    t: NDArray[np.float64]
    data: NDArray[np.float64]
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        if self.t.ndim != 1 or self.data.shape != (self.t.size, len(self.names)):
            raise MotosimError(
                f"{type(self).__name__}: t {self.t.shape} and data {self.data.shape} with "
                f"{len(self.names)} names; expected t (n,) and data (n, {len(self.names)})"
            )

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        """The column of the signal ``name`` (``"t"`` gives the time when not a column)."""
        if name == "t" and "t" not in self.names:
            return self.t
        try:
            return self.data[:, self.names.index(name)]
        except ValueError:
            raise KeyError(f"no signal {name!r}; have {', '.join(self.names)}") from None

    def get(self, name: str) -> NDArray[np.float64] | None:
        """The column of the signal ``name``, or None when the series does not have it."""
        return self[name] if name in self else None

    def __contains__(self, name: object) -> bool:
        """Whether the series has the signal ``name`` (``"t"`` included)."""
        return name == "t" or name in self.names
