"""The ``[realtime.safety]`` table of the scenarios that the real-time tests and benches write.

One place for the limits of the bench handlebar (those of ``scenarios/realtime_square.toml``,
without hands-off detection) that ``test_rt_cli``, :mod:`live_rig` and ``bench/bench_rt.py``
add to their scenario text; only the watchdog differs between them.
"""

__all__ = ["safety_table"]


def safety_table(watchdog_periods: int) -> str:
    """The ``[realtime.safety]`` table, TOML text, with ``watchdog_periods`` status periods.

    A lenient watchdog (100 periods or more) keeps a run on a busy machine without
    SCHED_FIFO going; the tests of the 3-period watchdog run lock-step.
    """
    return f"""
[realtime.safety]
max_current = 10.0
max_slew = 2000.0
max_speed = 6.0
speed_band = 4.0
soft_stop = 0.6
hard_stop = 0.8
end_stop_gain = 50.0
hands_off_torque = 0.0
hands_off_time = 1.0
hands_off_gain = 0.3
watchdog_periods = {watchdog_periods}
"""
