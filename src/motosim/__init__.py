"""motosim: software for motorcycle riding simulators with a motorised handlebar.

The package follows one data flow, each layer importing only from those before it::

    params -> model -> {identification, estimation, control} -> sim -> io
           -> {rt, plotting} -> report -> cli

Start with :func:`motosim.params.load_parameters` and :func:`motosim.model.sharp.linearize`.
"""

from motosim.errors import MotosimError

__version__ = "0.1.0"

__all__ = ["MotosimError", "__version__"]
