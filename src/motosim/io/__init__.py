"""Files in and out: logs as CSV, results, and (later) the CAN link."""

from motosim.io.logs import (
    ColumnSpec,
    LogTiming,
    RigLog,
    log_timing,
    parse_columns,
    read_log,
    read_rig_log,
    resample,
    write_log,
)

__all__ = [
    "ColumnSpec",
    "LogTiming",
    "RigLog",
    "log_timing",
    "parse_columns",
    "read_log",
    "read_rig_log",
    "resample",
    "write_log",
]
