"""AUTOSAR E2E Profile 1's check against the profile's cases: each counter sequence and its
statuses.

The rules are those of ``E2E_P01Check`` in the *Specification of SW-C End-to-End
Communication Protection Library* (AUTOSAR CP R4.2.2 and later, document 428) and in the
*E2E Protocol Specification* (AUTOSAR FO R20-11, document 849), Profile 1: the counter's
step modulo 15, the tolerance ``MaxDeltaCounter`` widened by one per call and reset to
``MaxDeltaCounterInit`` by a frame taken, the synchronisation after a ``WRONGSEQUENCE`` or
more than ``MaxNoNewOrRepeatedData`` calls without a new counter. ``None`` is a receive
cycle without a frame.
"""

import pytest

from motosim.errors import MotosimError
from motosim.rt.e2e import (
    INPUT_ERROR,
    MAX_COUNTER,
    E2EConfig,
    E2EReceiver,
    E2EStatus,
    e2e_check,
)

OK, NONEWDATA, WRONGCRC, SYNC = (
    E2EStatus.OK,
    E2EStatus.NONEWDATA,
    E2EStatus.WRONGCRC,
    E2EStatus.SYNC,
)
INITIAL, REPEATED = E2EStatus.INITIAL, E2EStatus.REPEATED
OKSOMELOST, WRONGSEQUENCE = E2EStatus.OKSOMELOST, E2EStatus.WRONGSEQUENCE


@pytest.mark.parametrize(
    ("counters", "settings", "expected"),
    [
        # the first frame, then one step at a time, round the counter's 15 values
        ([None, 3, 4, 5], {}, [NONEWDATA, INITIAL, OK, OK]),
        ([12, 13, 14, 0, 1], {}, [INITIAL, OK, OK, OK, OK]),
        # the counter has not moved
        ([6, 6, 7], {}, [INITIAL, REPEATED, OK]),
        # MaxDeltaCounterInit = 1: after counter 1, counters 2 and 3 are taken, 4 is not
        ([1, 3], {}, [INITIAL, OKSOMELOST]),
        ([1, 4], {}, [INITIAL, WRONGSEQUENCE]),
        ([14, 1], {}, [INITIAL, OKSOMELOST]),  # 14 -> 1: two steps modulo 15
        # a cycle without a frame widens the tolerance by one
        ([1, None, 4], {}, [INITIAL, NONEWDATA, OKSOMELOST]),
        ([1, None, 5], {}, [INITIAL, NONEWDATA, WRONGSEQUENCE]),
        # an older frame after a newer is a step of more than the tolerance
        ([5, 6, 4, 7], {}, [INITIAL, OK, WRONGSEQUENCE, OK]),
        # WRONGSEQUENCE without synchronisation (SyncCounterInit 0): the last valid counter
        # is kept
        ([1, 8, 2], {}, [INITIAL, WRONGSEQUENCE, OK]),
        # with SyncCounterInit 2: the frame's counter is taken as the last one, the next two
        # one step on are SYNC, then OK
        ([1, 8, 9, 10, 11], {"sync_counter_init": 2}, [INITIAL, WRONGSEQUENCE, SYNC, SYNC, OK]),
        ([1, 8, 2], {"sync_counter_init": 2}, [INITIAL, WRONGSEQUENCE, WRONGSEQUENCE]),
        # MaxNoNewOrRepeatedData 1: one cycle without a new counter is tolerated, two are not
        ([1, None, 2], {"max_no_new_or_repeated_data": 1}, [INITIAL, NONEWDATA, OK]),
        (
            [1, None, None, 2, 3],
            {"max_no_new_or_repeated_data": 1},
            [INITIAL, NONEWDATA, NONEWDATA, SYNC, OK],
        ),
        (
            [1, None, None, 2, 3, 4],
            {"max_no_new_or_repeated_data": 1, "sync_counter_init": 1},
            [INITIAL, NONEWDATA, NONEWDATA, SYNC, SYNC, OK],
        ),
        # repeated frames count as cycles without a new counter
        (
            [1, 1, 1, 2, 3],
            {"max_no_new_or_repeated_data": 1},
            [INITIAL, REPEATED, REPEATED, SYNC, OK],
        ),
        # a frame with a wrong CRC changes no counter
        ([1, -2, 2], {}, [INITIAL, WRONGCRC, OK]),
    ],
)
def test_the_profiles_statuses(
    counters: list[int | None], settings: dict[str, int], expected: list[E2EStatus]
) -> None:
    rx = E2EReceiver(
        E2EConfig(
            max_delta_counter_init=1,
            max_no_new_or_repeated_data=settings.get("max_no_new_or_repeated_data", 14),
            sync_counter_init=settings.get("sync_counter_init", 0),
        )
    )
    # a negative counter here is the frame of that counter with a wrong CRC
    got = [rx.check(c) if c is None or c >= 0 else rx.check(-c, crc_ok=False) for c in counters]
    assert got == expected


def test_lost_data_counts_the_frames_missing_before_the_one_taken() -> None:
    rx = E2EReceiver(
        E2EConfig(max_delta_counter_init=5, max_no_new_or_repeated_data=14, sync_counter_init=0)
    )
    assert [rx.check(c) for c in (2, 7)] == [INITIAL, OKSOMELOST]
    assert rx.snapshot().lost_data == 4
    assert rx.check(8) == OK and rx.snapshot().lost_data == 0


def test_the_tolerance_grows_per_call_to_at_most_14() -> None:
    rx = E2EReceiver(
        E2EConfig(max_delta_counter_init=0, max_no_new_or_repeated_data=14, sync_counter_init=0)
    )
    rx.check(0)
    assert rx.snapshot().max_delta_counter == 0
    for n in range(1, 20):
        rx.check(None)
        assert rx.snapshot().max_delta_counter == min(n, MAX_COUNTER)
    assert rx.check(14) == OKSOMELOST  # 14 steps: the widest the tolerance gets
    assert rx.snapshot().max_delta_counter == 0


def test_restart_waits_for_a_first_frame_again() -> None:
    rx = E2EReceiver(
        E2EConfig(max_delta_counter_init=1, max_no_new_or_repeated_data=14, sync_counter_init=0)
    )
    assert [rx.check(c) for c in (4, 5)] == [INITIAL, OK]
    rx.restart()
    assert rx.check(11) == INITIAL and rx.check(12) == OK


def test_an_invalid_counter_is_an_input_error_that_changes_nothing() -> None:
    rx = E2EReceiver(
        E2EConfig(max_delta_counter_init=1, max_no_new_or_repeated_data=14, sync_counter_init=0)
    )
    rx.check(3)
    assert e2e_check(rx.state, True, True, 15) == INPUT_ERROR
    assert rx.status == INITIAL and rx.snapshot().last_valid_counter == 3
    with pytest.raises(MotosimError, match=r"E2E counter = 15; expected an integer from 0 to 14"):
        rx.check(15)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("max_delta_counter_init", 15),
        ("sync_counter_init", -1),
        ("max_no_new_or_repeated_data", 1.0),
    ],
)
def test_bad_settings_are_refused(key: str, value: object) -> None:
    settings: dict[str, object] = {
        "max_delta_counter_init": 1,
        "max_no_new_or_repeated_data": 1,
        "sync_counter_init": 1,
    } | {key: value}
    with pytest.raises(MotosimError, match=rf"E2E {key} = .*; expected an integer from 0 to 14"):
        E2EConfig(**settings)  # type: ignore[arg-type]
