"""Files in and out: logs as CSV, results, and (later) the CAN link."""

from motosim.io.logs import read_log, write_log

__all__ = ["read_log", "write_log"]
