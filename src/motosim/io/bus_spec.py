"""A bus given as ``INTERFACE[:CHANNEL]`` (``--bus``), checked without loading the CAN codec.

:func:`check_bus` is what ``motosim run`` and ``motosim rig`` refuse a bus with before any
heavy import (the codec of :mod:`motosim.io.can` is compiled with numba), and what
:func:`motosim.io.can.open_link` checks again when it opens the bus.
"""

import ipaddress

from motosim.errors import MotosimError

__all__ = ["check_bus"]


def check_bus(spec: str) -> tuple[str, str]:
    """``INTERFACE[:CHANNEL]`` split and checked against python-can's interfaces.

    Raises
    ------
    MotosimError
        If the interface is not one python-can knows, or python-can is not installed.
    """
    interface, _, channel = spec.partition(":")
    try:
        from can.interfaces import VALID_INTERFACES
    except ImportError:
        raise MotosimError(
            "python-can is not installed; install motosim's rt group: pip install 'motosim[rt]'"
        ) from None
    if interface not in VALID_INTERFACES:
        shown = spec if len(spec) <= 40 else spec[:37] + "..."
        raise MotosimError(
            f"--bus {shown!r}; expected INTERFACE[:CHANNEL] with a python-can interface such as "
            "socketcan:can0, virtual or udp_multicast"
        )
    if interface == "udp_multicast" and channel and not _is_multicast(channel):
        # python-can failed on it after half opening the bus: two more lines
        shown = channel if len(channel) <= 40 else channel[:37] + "..."
        raise MotosimError(
            f"--bus 'udp_multicast:{shown}'; expected a multicast group address as the "
            "channel, such as udp_multicast:239.74.163.79 (224.0.0.0 to 239.255.255.255) or "
            "an IPv6 ff00::/8 address"
        )
    return interface, channel


def _is_multicast(address: str) -> bool:
    try:
        return ipaddress.ip_address(address.strip("[]")).is_multicast
    except ValueError:
        return False
