"""Field specifications: unit, meaning and admissible range of each physical parameter.

Every range is physical, not only a sign: a value outside it is not a motorcycle or a
handlebar this software can represent (or a unit slip such as grams for kilograms), and is
refused before it reaches a model. Each :class:`Spec` says why its bounds are where they are.
"""

import math
from dataclasses import dataclass, fields
from typing import ClassVar, Protocol

from motosim.params.checks import check_number, describe_range

__all__ = ["Spec", "atypical_fields", "validate_fields"]


@dataclass(frozen=True, slots=True)
class Spec:
    """Unit, meaning and admissible open or closed interval of one parameter.

    Attributes
    ----------
    unit : str
        SI unit, as written in parameter files.
    description : str
        What the quantity is.
    lower, upper : float
        Bounds of the admissible interval.
    lower_closed, upper_closed : bool
        Whether each bound is admitted.
    reason : str
        Why the bounds are where they are (the physical argument).
    """

    unit: str
    description: str
    lower: float = -math.inf
    lower_closed: bool = False
    upper: float = math.inf
    upper_closed: bool = False
    reason: str = ""

    @classmethod
    def between(
        cls, unit: str, description: str, lower: float, upper: float, *, reason: str
    ) -> "Spec":
        """A quantity in the closed interval [lower, upper], with the reason for the bounds."""
        return cls(
            unit,
            description,
            lower,
            lower_closed=True,
            upper=upper,
            upper_closed=True,
            reason=reason,
        )

    @classmethod
    def positive(cls, unit: str, description: str) -> "Spec":
        """A quantity that must be > 0."""
        return cls(unit, description, lower=0.0)

    @classmethod
    def non_negative(cls, unit: str, description: str) -> "Spec":
        """A quantity that must be >= 0."""
        return cls(unit, description, lower=0.0, lower_closed=True)

    def expected(self) -> str:
        """Describe the admissible range in words, e.g. ``a finite number > 0 [kg]``."""
        return describe_range(
            self.lower,
            self.upper,
            lower_closed=self.lower_closed,
            upper_closed=self.upper_closed,
            unit=self.unit,
        )

    def admits(self, value: float) -> bool:
        """Return True when ``value`` is finite and inside the interval."""
        if not math.isfinite(value):
            return False
        above = value >= self.lower if self.lower_closed else value > self.lower
        below = value <= self.upper if self.upper_closed else value < self.upper
        return above and below


class _HasSpecs(Protocol):
    SPECS: ClassVar[dict[str, Spec]]


class _HasTypical(Protocol):
    SPECS: ClassVar[dict[str, Spec]]
    TYPICAL: ClassVar[dict[str, tuple[float, float, str]]]


def validate_fields(obj: _HasSpecs, *, context: str) -> None:
    """Check every dataclass field of ``obj`` against its :class:`Spec`.

    Parameters
    ----------
    obj : dataclass instance with a ``SPECS`` class attribute
        The parameters to check.
    context : str
        What the parameters are, for the message (e.g. ``"Sharp parameters"``).

    Raises
    ------
    MotosimError
        Naming the first field whose value is not a finite number in its range.
    """
    for f in fields(obj):  # type: ignore[arg-type]
        spec = obj.SPECS[f.name]
        check_number(
            getattr(obj, f.name),
            where=f"{context}: {f.name}",
            lower=spec.lower,
            upper=spec.upper,
            lower_closed=spec.lower_closed,
            upper_closed=spec.upper_closed,
            unit=spec.unit,
        )


def atypical_fields(obj: _HasTypical, *, context: str) -> list[str]:
    """One line for each field of ``obj`` that is legal but outside its typical range.

    Parameters
    ----------
    obj : dataclass instance with ``SPECS`` and ``TYPICAL`` class attributes
        The validated parameters; ``TYPICAL`` maps a field to (low, high, what has values
        in that range).
    context : str
        What the parameters are, for the message.

    Returns
    -------
    list of str
        The warnings, empty when every value is typical.
    """
    lines = []
    for name, (low, high, why) in obj.TYPICAL.items():
        value = float(getattr(obj, name))
        if not low <= value <= high:
            unit = obj.SPECS[name].unit
            lines.append(
                f"{context}: {name} = {value:g} {unit} is legal but outside the typical "
                f"{low:g} to {high:g} {unit} ({why}); check the value and its unit"
            )
    return lines
