"""The receiver's check of AUTOSAR E2E Profile 1 (the counter and its statuses), compiled.

AUTOSAR's E2E Profile 1 protects a periodic frame with a CRC and a 4-bit counter. Its check
(``E2E_P01Check`` of the *Specification of SW-C End-to-End Communication Protection
Library*, AUTOSAR CP R4.2.2 and later, document 428; the same machine in the *E2E Protocol
Specification*, AUTOSAR FO R20-11, document 849, Profile 1) is called once per receive
cycle, with or without a new frame, and gives each call one status:

- ``NONEWDATA``: no new frame this cycle;
- ``WRONGCRC``: a frame whose CRC is wrong (the counter state is left as it is);
- ``INITIAL``: the first frame with a right CRC since the start (or :func:`e2e_restart`);
- ``REPEATED``: the counter has not moved;
- ``OK``: the counter moved by one;
- ``OKSOMELOST``: it moved by 2 to ``MaxDeltaCounter`` (``DeltaCounter - 1`` frames lost);
- ``WRONGSEQUENCE``: it moved by more (too many lost, or an older frame after a newer);
- ``SYNC``: the counter moved by 1 to ``MaxDeltaCounter``, but the receiver is synchronising
  again after a ``WRONGSEQUENCE`` or after more than ``MaxNoNewOrRepeatedData`` cycles in a
  row with no frame or a repeated one: the data are not yet taken as valid.

The counter runs from 0 to 14 (:data:`MAX_COUNTER`; 15 is no valid counter and the call
gives :data:`INPUT_ERROR`) and the counter's step is counted modulo 15. The tolerance
``MaxDeltaCounter`` goes up by one at every call (to at most 14) and back to
``MaxDeltaCounterInit`` at every frame taken, so that the cycles without a frame widen the
step the next frame may make. A ``WRONGSEQUENCE`` with ``SyncCounterInit`` > 0 takes the
frame's counter as the last one and starts the synchronisation: ``SyncCounterInit`` frames
more, each one step on, are ``SYNC`` before the next is ``OK``. After more than
``MaxNoNewOrRepeatedData`` cycles without a new counter, the first frame taken is ``SYNC``
and ``SyncCounterInit`` frames more after it.

The CRC itself (CRC-8 SAE J1850 over the data identifier and the frame) is the caller's: the
check is told whether it was right.
"""

from dataclasses import dataclass, fields
from enum import IntEnum
from typing import Any, NamedTuple

from numba import njit
from numba.core import types
from numba.experimental import structref

from motosim.errors import MotosimError
from motosim.params.checks import short_repr

__all__ = [
    "INPUT_ERROR",
    "MAX_COUNTER",
    "E2EConfig",
    "E2EReceiver",
    "E2ESnapshot",
    "E2EState",
    "E2EStatus",
    "FieldsStruct",
    "e2e_check",
    "e2e_restart",
]


class E2EStatus(IntEnum):
    """The status of one check (``E2E_P01CheckStatusType``, its values since R4.3.1)."""

    OK = 0
    NONEWDATA = 1
    WRONGCRC = 2
    SYNC = 3
    INITIAL = 4
    REPEATED = 5
    OKSOMELOST = 6
    WRONGSEQUENCE = 7


MAX_COUNTER = 14
"""The largest value of Profile 1's counter (0 to 14; 15 is invalid)."""
INPUT_ERROR = -1
"""What :func:`e2e_check` returns for a counter outside 0 to :data:`MAX_COUNTER` (the
profile's ``E2E_E_INPUTERR_WRONG``): the status and the counter state are not changed."""


@dataclass(frozen=True, slots=True)
class E2EConfig:
    """The receiver's settings of Profile 1 (``E2E_P01ConfigType``'s counter part).

    Parameters
    ----------
    max_delta_counter_init : int
        ``MaxDeltaCounterInit``: the largest step of the counter taken at the call after a
        frame taken, less one (the tolerance goes up by one per call), 0 to 14.
    max_no_new_or_repeated_data : int
        ``MaxNoNewOrRepeatedData``: the calls in a row without a new counter (no frame, or
        a repeated one) after which the receiver synchronises again, 0 to 14.
    sync_counter_init : int
        ``SyncCounterInit``: the frames one step on that are ``SYNC`` before ``OK`` when the
        receiver synchronises again, 0 to 14.
    """

    max_delta_counter_init: int
    max_no_new_or_repeated_data: int
    sync_counter_init: int

    def __post_init__(self) -> None:
        for name in _SETTINGS:
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, int) and 0 <= value <= 14):
                raise MotosimError(
                    f"E2E {name} = {short_repr(value)}; expected an integer from 0 to 14"
                )


class E2ESnapshot(NamedTuple):
    """The counter part of an :class:`E2EState`, read at one instant."""

    last_valid_counter: int
    max_delta_counter: int
    wait_for_first_data: bool
    lost_data: int
    status: int
    sync_counter: int
    no_new_or_repeated_data_counter: int


_SETTINGS = tuple(f.name for f in fields(E2EConfig))


class FieldsStruct(types.StructRef):
    """A numba ``structref`` type whose fields' types are taken without literal values."""

    def preprocess_fields(self, fields: Any) -> tuple[tuple[str, Any], ...]:
        """The fields' types without literal values."""
        return tuple((name, types.unliteral(typ)) for name, typ in fields)  # type: ignore[no-untyped-call]


@structref.register
class E2EStateType(FieldsStruct):
    """numba's type of :class:`E2EState`."""


class E2EState(structref.StructRefProxy):
    """The receiver's state of Profile 1 (``E2E_P01CheckStateType``), shared with compiled
    code.

    Fields (read in compiled code; from Python through :class:`E2EReceiver`):
    ``last_valid_counter``, ``max_delta_counter``, ``wait_for_first_data``, ``lost_data``
    (frames lost before the last one taken), ``status`` (:class:`E2EStatus`),
    ``sync_counter``, ``no_new_or_repeated_data_counter``, then the fields of :class:`E2EConfig`.
    """

    def __new__(cls, config: E2EConfig) -> "E2EState":
        settings = (getattr(config, name) for name in _SETTINGS)
        made: E2EState = structref.StructRefProxy.__new__(  # type: ignore[no-untyped-call]
            cls, 0, 0, True, 0, int(E2EStatus.NONEWDATA), 0, 0, *settings
        )
        return made


structref.define_proxy(  # type: ignore[no-untyped-call]
    E2EState, E2EStateType, [*E2ESnapshot._fields, *_SETTINGS]
)


@njit(cache=True)
def e2e_restart(st: Any) -> None:
    """Start the receiver afresh (``E2E_P01CheckInit``): the next frame is ``INITIAL``."""
    st.last_valid_counter = 0
    st.max_delta_counter = 0
    st.wait_for_first_data = True
    st.lost_data = 0
    st.status = E2EStatus.NONEWDATA
    st.sync_counter = 0
    st.no_new_or_repeated_data_counter = 0


@njit(cache=True, inline="always")
def _taken(st: Any, counter: int, delta: int, clean: int) -> int:
    """A frame taken ``delta`` counts on: ``clean`` (OK or OKSOMELOST) or SYNC while the
    receiver synchronises."""
    st.max_delta_counter = st.max_delta_counter_init
    st.last_valid_counter = counter
    st.lost_data = delta - 1
    sync = True
    if st.no_new_or_repeated_data_counter <= st.max_no_new_or_repeated_data:
        if st.sync_counter > 0:
            st.sync_counter -= 1
        else:
            sync = False
    else:
        st.sync_counter = st.sync_counter_init
    st.no_new_or_repeated_data_counter = 0
    return E2EStatus.SYNC if sync else clean


@njit(cache=True)
def e2e_check(st: Any, new_data: bool, crc_ok: bool, counter: int) -> int:
    """One receive cycle of ``E2E_P01Check`` on the receiver's state ``st`` (updated in
    place): its :class:`E2EStatus` code (also kept in ``st.status``), or :data:`INPUT_ERROR`
    for a ``counter`` outside 0 to :data:`MAX_COUNTER`. ``new_data``: whether a frame came
    this cycle (else ``crc_ok``, whether its CRC is right, and ``counter`` are unread)."""
    st.max_delta_counter = min(st.max_delta_counter + 1, MAX_COUNTER)
    if not new_data:
        st.no_new_or_repeated_data_counter = min(
            st.no_new_or_repeated_data_counter + 1, MAX_COUNTER
        )
        st.status = E2EStatus.NONEWDATA
        return E2EStatus.NONEWDATA
    if counter < 0 or counter > MAX_COUNTER:
        return INPUT_ERROR
    if not crc_ok:
        st.status = E2EStatus.WRONGCRC
        return E2EStatus.WRONGCRC
    if st.wait_for_first_data:
        st.wait_for_first_data = False
        st.max_delta_counter = st.max_delta_counter_init
        st.last_valid_counter = counter
        st.status = E2EStatus.INITIAL
        return E2EStatus.INITIAL
    delta = (counter - st.last_valid_counter) % (MAX_COUNTER + 1)
    status: int
    if delta == 0:
        st.no_new_or_repeated_data_counter = min(
            st.no_new_or_repeated_data_counter + 1, MAX_COUNTER
        )
        status = E2EStatus.REPEATED
    elif delta == 1:
        status = _taken(st, counter, delta, E2EStatus.OK)
    elif delta <= st.max_delta_counter:
        status = _taken(st, counter, delta, E2EStatus.OKSOMELOST)
    else:
        st.no_new_or_repeated_data_counter = 0
        st.sync_counter = st.sync_counter_init
        if st.sync_counter > 0:
            st.max_delta_counter = st.max_delta_counter_init
            st.last_valid_counter = counter
        status = E2EStatus.WRONGSEQUENCE
    st.status = status
    return status


@njit(cache=True)
def _snapshot(st: Any) -> E2ESnapshot:
    """The state's counter fields, for Python."""
    return E2ESnapshot(
        st.last_valid_counter,
        st.max_delta_counter,
        st.wait_for_first_data,
        st.lost_data,
        st.status,
        st.sync_counter,
        st.no_new_or_repeated_data_counter,
    )


class E2EReceiver:
    """The receiving end of one Profile 1 frame: :meth:`check` once per receive cycle.

    Parameters
    ----------
    config : E2EConfig
        The receiver's settings.

    Examples
    --------
    >>> rx = E2EReceiver(E2EConfig(max_delta_counter_init=1, max_no_new_or_repeated_data=2,
    ...                            sync_counter_init=1))
    >>> [rx.check(c).name for c in (3, 4, 4, 6, 10)]
    ['INITIAL', 'OK', 'REPEATED', 'OKSOMELOST', 'WRONGSEQUENCE']
    >>> rx.check(None).name, rx.check(11).name, rx.check(12).name
    ('NONEWDATA', 'SYNC', 'OK')
    """

    __slots__ = ("config", "state")

    def __init__(self, config: E2EConfig) -> None:
        self.config = config
        self.state = E2EState(config)

    def check(self, counter: int | None, *, crc_ok: bool = True) -> E2EStatus:
        """The status of this cycle's frame with ``counter`` (None: no frame this cycle).

        Raises
        ------
        MotosimError
            For a counter outside 0 to :data:`MAX_COUNTER`.
        """
        if counter is None:
            return E2EStatus(e2e_check(self.state, False, True, 0))
        if isinstance(counter, bool) or not (
            isinstance(counter, int) and 0 <= counter <= MAX_COUNTER
        ):
            raise MotosimError(
                f"E2E counter = {short_repr(counter)}; expected an integer from 0 to {MAX_COUNTER}"
            )
        return E2EStatus(e2e_check(self.state, True, bool(crc_ok), counter))

    def restart(self) -> None:
        """Start afresh: the next frame is ``INITIAL``."""
        e2e_restart(self.state)

    def snapshot(self) -> E2ESnapshot:
        """The receiver's counters now."""
        return _snapshot(self.state)

    @property
    def status(self) -> E2EStatus:
        """The last call's status."""
        return E2EStatus(self.snapshot().status)
