"""Files in and out: logs as CSV, results, atomic files and folder locks, the CAN link.

The package's own names are those of :mod:`motosim.io.logs` (the logs every command reads);
the other modules are imported by name (:mod:`motosim.io.results`, :mod:`motosim.io.files`...).
"""

from motosim.io.logs import *  # noqa: F403
from motosim.io.logs import __all__ as __all__
