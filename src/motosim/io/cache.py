"""A content-addressed cache of designs: each design computed once, then read back.

A design (a controller synthesis, the virtual rider's gain schedule, the stack's model) is
a pure function of its inputs, so it is stored under a key that hashes all of them: the
inputs as canonical JSON (floats by their exact ``repr``), the kind of design, motosim's
version and a hash of the source of the modules that design (:data:`DESIGN_PACKAGES`). A
change of any input, of the version or of the design code gives another key; nothing is
ever invalidated by hand.

An entry is one ``.npz`` file of arrays and scalars (read with ``allow_pickle=False``: no
code is ever loaded from the cache), named ``KIND-KEY.npz`` and written under a temporary
name in the cache folder then renamed (:func:`os.replace`), so two processes storing the
same key leave one whole entry. An entry that cannot be read is designed again, with a
warning, and replaced.

The folder is ``$MOTOSIM_CACHE_DIR``, else ``$XDG_CACHE_HOME/motosim``, else
``~/.cache/motosim`` (:func:`cache_folder`). The library's design functions know nothing of
it: :mod:`motosim.io.runs` and the command line pass a :class:`DesignCache` in.
"""

import contextlib
import dataclasses
import functools
import hashlib
import json
import math
import os
import tempfile
import time
import types
import typing
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, NamedTuple, TypeVar
from zipfile import BadZipFile

import numpy as np

from motosim import __version__
from motosim.errors import MotosimError, warn

if typing.TYPE_CHECKING:
    from motosim.model.linear import StateSpace
    from motosim.params import HandlebarParameters
    from motosim.sim.closed_loop import RunInputs
    from motosim.sim.multibody_rider import MultibodyRider
    from motosim.sim.rider import RiderGains
    from motosim.sim.stack import StackModel

__all__ = [
    "CACHE_ENV",
    "DESIGN_PACKAGES",
    "CacheInfo",
    "DesignCache",
    "cache_folder",
    "cached_controller",
    "cached_rider",
    "cached_stack",
    "design_key",
    "from_arrays",
    "source_hash",
    "to_arrays",
]

CACHE_ENV = "MOTOSIM_CACHE_DIR"
"""Environment variable naming the cache folder (the test suite points it at a temporary one)."""

DESIGN_PACKAGES = ("control", "estimation", "model", "params", "sim", "io/cache.py", "io/runs.py")
"""The parts of motosim whose source the designs depend on (packages or files), hashed into
every key."""

SUFFIX = ".npz"

_UNREADABLE = (OSError, ValueError, KeyError, TypeError, AttributeError, EOFError, BadZipFile)
"""What reading an entry raises when the file is not one :func:`to_arrays` stored."""

T = TypeVar("T")


def cache_folder(environ: Mapping[str, str] | None = None) -> Path:
    """The user's cache folder of motosim's designs (it need not exist yet).

    ``$MOTOSIM_CACHE_DIR``, else ``$XDG_CACHE_HOME/motosim``, else ``~/.cache/motosim``.
    """
    env = os.environ if environ is None else environ
    if env.get(CACHE_ENV):
        return Path(env[CACHE_ENV]).expanduser()
    xdg = env.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "motosim"


@functools.cache
def source_hash() -> str:
    """SHA-256 of the source files of :data:`DESIGN_PACKAGES`, in path order."""
    root = Path(__file__).resolve().parents[1]
    files: list[Path] = []
    for part in DESIGN_PACKAGES:
        path = root / part
        files += sorted(path.rglob("*.py")) if path.is_dir() else [path]
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _plain(value: Any) -> Any:
    """``value`` as JSON-able data that tells apart everything a design can depend on."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        x = float(value)
        return repr(x) if not math.isfinite(x) else x
    if isinstance(value, np.ndarray):
        return {
            "dtype": value.dtype.str,
            "shape": list(value.shape),
            "data": _plain(value.tolist()),
        }
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            "type": type(value).__name__,
            **{f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)},
        }
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return {
            "type": type(value).__name__,
            **{k: _plain(getattr(value, k)) for k in value._fields},
        }
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"design input of type {type(value).__name__} cannot be hashed")


def design_key(kind: str, depends_on: Mapping[str, Any]) -> str:
    """The cache key of a design of ``kind`` from its inputs ``depends_on``.

    SHA-256 of canonical JSON of the kind, the inputs (dataclasses, named tuples and arrays
    field by field, floats exactly), motosim's version and :func:`source_hash`.

    Examples
    --------
    >>> design_key("x", {"rate": 1000.0}) == design_key("x", {"rate": 1000.0})
    True
    >>> design_key("x", {"rate": 1000.0}) == design_key("x", {"rate": 1000.0000000001})
    False
    """
    text = json.dumps(
        {
            "kind": kind,
            "version": __version__,
            "source": source_hash(),
            "inputs": _plain(depends_on),
        },
        sort_keys=True,
        separators=(",", ":"),
        allow_nan=False,
    )
    return hashlib.sha256(text.encode()).hexdigest()


def to_arrays(value: Any, prefix: str = "") -> dict[str, np.ndarray]:
    """A dataclass or named tuple (nested ones included) as named arrays for ``.npz``.

    Scalars become 0-d arrays, tuples of strings 1-d string arrays.
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        names = [f.name for f in dataclasses.fields(value)]
    else:
        names = list(value._fields)
    out: dict[str, np.ndarray] = {}
    for name in names:
        field = getattr(value, name)
        key = f"{prefix}{name}"
        if dataclasses.is_dataclass(field) or (
            isinstance(field, tuple) and hasattr(field, "_fields")
        ):
            out.update(to_arrays(field, f"{key}."))
        elif isinstance(field, tuple):
            out[key] = np.array([str(v) for v in field], dtype=str)
        else:
            out[key] = np.asarray(field)
    return out


def from_arrays(cls: type[T], arrays: Mapping[str, np.ndarray], prefix: str = "") -> T:
    """The ``cls`` that :func:`to_arrays` stored (``KeyError`` or ``TypeError`` when it does not
    fit ``cls``'s fields)."""
    hints = typing.get_type_hints(cls)
    if dataclasses.is_dataclass(cls):
        names = [f.name for f in dataclasses.fields(cls) if f.init]
    else:
        names = list(typing.cast(Any, cls)._fields)
    values: dict[str, Any] = {}
    for name in names:
        hint = hints[name]
        key = f"{prefix}{name}"
        origin = typing.get_origin(hint)
        if origin is None and (dataclasses.is_dataclass(hint) or hasattr(hint, "_fields")):
            values[name] = from_arrays(hint, arrays, f"{key}.")
            continue
        if origin in (typing.Union, types.UnionType):  # one of several records: the one stored
            for member in typing.get_args(hint):
                try:
                    values[name] = from_arrays(member, arrays, f"{key}.")
                    break
                except (KeyError, TypeError):
                    continue
            else:
                raise KeyError(f"{key}: stored as none of {hint}")
            continue
        stored = arrays[key]
        if hint in (bool, int, float):
            values[name] = hint(stored.item())
        elif origin is tuple:
            values[name] = tuple(str(v) for v in stored.tolist())
        else:
            if stored.dtype.kind not in "fiub":
                raise TypeError(f"{key}: stored as {stored.dtype}, expected numbers")
            values[name] = np.array(stored)
    return cls(**values)


class CacheInfo(NamedTuple):
    """What a cache folder holds: its path, entries by kind, and their size [bytes]."""

    folder: Path
    entries: dict[str, int]
    size: int


class DesignCache:
    """Designs stored by content in a folder (or, with ``folder = None``, always designed).

    Parameters
    ----------
    folder : str or Path or None
        The cache folder (created when an entry is first stored); None turns the cache off:
        :meth:`fetch` designs every time and stores nothing (``--no-cache``).
    on_design : callable, optional
        Told when a :meth:`designing` block designs something: ``on_design(label, None)``
        at its first design, ``on_design(label, seconds)`` at its end (for the command
        line's one line "designing ..., 2.3 s").
    """

    def __init__(
        self,
        folder: str | Path | None,
        *,
        on_design: Callable[[str, float | None], None] | None = None,
    ) -> None:
        self.folder = None if folder is None else Path(folder)
        self.on_design = on_design
        self._label: str | None = None
        self._started: float | None = None

    @classmethod
    def default(
        cls, *, enabled: bool = True, on_design: Callable[[str, float | None], None] | None = None
    ) -> "DesignCache":
        """The user's cache (:func:`cache_folder`), or a disabled one."""
        return cls(cache_folder() if enabled else None, on_design=on_design)

    def path(self, kind: str, key: str) -> Path | None:
        """The entry's file (None when the cache is off)."""
        return None if self.folder is None else self.folder / f"{kind}-{key}{SUFFIX}"

    @contextlib.contextmanager
    def designing(self, label: str) -> Iterator[None]:
        """Group the designs of one run (``label``, e.g. the scenario's name) for ``on_design``."""
        outer = self._label is not None
        if not outer:
            self._label, self._started = label, None
        try:
            yield
        finally:
            if not outer:
                started, self._label, self._started = self._started, None, None
                if started is not None and self.on_design is not None:
                    self.on_design(label, time.perf_counter() - started)

    def _note_design(self) -> None:
        if self._label is not None and self._started is None:
            self._started = time.perf_counter()
            if self.on_design is not None:
                self.on_design(self._label, None)

    def fetch(
        self, kind: str, depends_on: Mapping[str, Any], compute: Callable[[], T], cls: type[T]
    ) -> T:
        """The design of ``kind`` for ``depends_on``: read from the cache, else computed.

        Parameters
        ----------
        kind : str
            What is designed (a file name's prefix: letters, digits, ``_``).
        depends_on : Mapping
            Every input of ``compute`` (hashed by :func:`design_key`).
        compute : callable
            Designs it (a pure function of ``depends_on``).
        cls : type
            The design's class (a dataclass or named tuple of arrays and scalars).

        Returns
        -------
        The design, bit for bit what ``compute`` returns.
        """
        path = None if self.folder is None else self.path(kind, design_key(kind, depends_on))
        if path is not None and path.is_file():
            try:
                with path.open("rb") as handle, np.load(handle, allow_pickle=False) as stored:
                    return from_arrays(cls, {k: stored[k] for k in stored.files})
            except _UNREADABLE as err:
                warn(f"design cache: {path} cannot be read ({err}); designing it again")
        self._note_design()
        design = compute()
        if path is not None:
            self._store(path, to_arrays(design))
        return design

    def _store(self, path: Path, arrays: Mapping[str, np.ndarray]) -> None:
        """Write ``arrays`` to ``path`` atomically; a cache that cannot be written is skipped."""
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".tmp")
        except OSError as err:
            warn(f"design cache: cannot write in {path.parent} ({err.strerror}); not cached")
            return
        try:
            save: Any = np.savez  # numbers and strings only: nothing is pickled
            with os.fdopen(fd, "wb") as handle:
                save(handle, **arrays)
            os.replace(tmp, path)
        except OSError as err:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            warn(f"design cache: cannot write {path} ({err.strerror}); not cached")

    def info(self) -> CacheInfo:
        """The folder, its entries by kind and their total size."""
        if self.folder is None:
            raise MotosimError("the design cache is off")
        entries: dict[str, int] = {}
        size = 0
        if self.folder.is_dir():
            for path in self.folder.glob(f"*{SUFFIX}"):
                kind = path.name.rsplit("-", 1)[0]
                entries[kind] = entries.get(kind, 0) + 1
                size += path.stat().st_size
        return CacheInfo(self.folder, dict(sorted(entries.items())), size)

    def clear(self) -> int:
        """Remove every entry (and leftover temporary file); returns the entries removed."""
        if self.folder is None or not self.folder.is_dir():
            return 0
        removed = 0
        for path in self.folder.iterdir():
            if path.suffix == SUFFIX or (path.name.startswith(".") and path.suffix == ".tmp"):
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                    removed += path.suffix == SUFFIX
        return removed


def cached_controller(
    cache: DesignCache,
    compute: Callable[[], "StateSpace"],
    *,
    handlebar: "HandlebarParameters",
    settings: Mapping[str, Any],
) -> "StateSpace":
    """The controller ``compute`` designs for ``handlebar`` with ``settings`` (its every
    other input: rate, bandwidth, order, integral corner, starts, seed), through ``cache``."""
    from motosim.model.linear import StateSpace

    return cache.fetch("controller", {"handlebar": handlebar, **settings}, compute, StateSpace)


def cached_rider(cache: DesignCache, inputs: "RunInputs") -> "RiderGains | MultibodyRider":
    """The virtual rider's schedule of a run
    (:func:`motosim.sim.closed_loop.design_virtual_rider`)."""
    from motosim.sim.closed_loop import rider_design
    from motosim.sim.multibody_rider import MultibodyRider, design_multibody_rider
    from motosim.sim.rider import RiderGains, design_rider

    settings = rider_design(inputs.scenario)
    multibody = inputs.multibody
    if multibody is not None and inputs.scenario.rider.kind == "virtual":
        return cache.fetch(
            "multibody_rider",
            {"multibody": multibody, **settings},
            lambda: design_multibody_rider(multibody, **settings),
            MultibodyRider,
        )
    sharp = inputs.sharp
    return cache.fetch(
        "rider", {"sharp": sharp, **settings}, lambda: design_rider(sharp, **settings), RiderGains
    )


def cached_stack(cache: DesignCache, inputs: "RunInputs") -> "StackModel":
    """The stack of a run (:func:`motosim.sim.build_stack`), keyed by the whole scenario and
    the designed parts it is built from."""
    from motosim.sim import build_stack
    from motosim.sim.scenario import scenario_dict
    from motosim.sim.stack import StackModel

    depends_on = {
        "scenario": scenario_dict(inputs.scenario),
        "sharp": inputs.sharp,
        "multibody": inputs.multibody,
        "nominal_handlebar": inputs.nominal_handlebar,
        "controller": inputs.controller,
        "observer": inputs.observer,
    }
    return cache.fetch("stack", depends_on, lambda: build_stack(inputs), StackModel)
