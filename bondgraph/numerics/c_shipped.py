"""Compiled C libraries carried from one process to another, so the second needs no compiler.

A sweep's client builds every C kernel once (:mod:`bondgraph.numerics.c_build`) and
ships the libraries to its workers (``docs/sweeps.md``).  While a
:func:`recording` is open, every library that :mod:`bondgraph.numerics.c_build` hands
out is noted under its *lookup key*: a hash of what the library was made from
that does not depend on the compiler (``src:`` the source, ``eqs:`` the state
equations and part, ``ukf:`` a UKF configuration).  :meth:`Recording.bundle`
reads those libraries into a :class:`KernelBundle`, a picklable value.  In the
other process :meth:`KernelBundle.install` writes each library once (by the
sha256 of its bytes) under :func:`shipped_dir` and registers its keys; from
then on :func:`bondgraph.numerics.c_build.compile_source`,
:func:`~bondgraph.numerics.c_build.build_library` and the UKF's C engine look the key up
(:func:`lookup`) before they look for a compiler, so they load the shipped
library and neither generate code nor compile.  A key the bundle lacks falls
back to compiling as before.

A library only runs on the platform it was built for: a bundle from another
platform (:data:`PLATFORM`) installs nothing, and that process compiles.
"""
from __future__ import annotations

import hashlib
import os
import platform
import sys
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from types import MappingProxyType

__all__ = ["KernelBundle", "Recording", "recording", "recording_open", "note", "lookup", "installed", "shipped_dir",
           "PLATFORM"]

#: Where a library can run: operating system and machine (``linux-x86_64``).
PLATFORM = f"{sys.platform}-{platform.machine()}"

_INSTALLED: dict[str, Path] = {}        # lookup key -> library file of this process
_BUNDLES: set[str] = set()              # digests of the bundles installed here
_RECORDINGS: list["Recording"] = []


def shipped_dir() -> Path:
    """Directory of installed libraries: ``<temp>/bondcosim-shipped-<uid>`` (shared by a node's workers)."""
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    return Path(tempfile.gettempdir()) / f"bondcosim-shipped-{uid}"


def lookup(key: str) -> Path | None:
    """The installed library of lookup `key`, or None (then the caller builds it)."""
    return _INSTALLED.get(key)


def installed() -> MappingProxyType:
    """Lookup key -> library file of every library installed in this process (read-only)."""
    return MappingProxyType(_INSTALLED)


def recording_open() -> bool:
    """True inside a :func:`recording` (callers skip computing keys otherwise)."""
    return bool(_RECORDINGS)


def note(key: str, path) -> None:
    """Tell the open recordings that `key` is served by the library at `path` (:mod:`bondgraph.numerics.c_build`)."""
    for rec in _RECORDINGS:
        rec.libraries[key] = Path(path)


@dataclass(frozen=True)
class KernelBundle:
    """Compiled libraries and the keys they serve, to :meth:`install` in another process.

    Attributes
    ----------
    libraries : dict str -> bytes
        sha256 (40 hex digits) of a shared library -> its bytes.
    keys : dict str -> str
        Lookup key -> sha256 of its library.
    platform : str
        :data:`PLATFORM` of the process that built them.
    """

    libraries: dict = field(default_factory=dict)
    keys: dict = field(default_factory=dict)
    platform: str = PLATFORM

    @property
    def nbytes(self) -> int:
        """Bytes of library code carried (B)."""
        return sum(len(b) for b in self.libraries.values())

    @cached_property
    def digest(self) -> str:
        """sha256 of the keys and libraries: installing the same bundle twice does nothing."""
        h = hashlib.sha256(self.platform.encode())
        for key in sorted(self.keys):
            h.update(f"\0{key}={self.keys[key]}".encode())
        return h.hexdigest()[:40]

    def install(self) -> int:
        """Write the libraries (once per node, by hash) and register their keys in this process.

        Returns
        -------
        int
            Keys registered now: 0 when the bundle was installed before, is
            empty, or was built on another platform (this process then compiles).
        """
        if not self.keys or self.platform != PLATFORM or self.digest in _BUNDLES:
            return 0
        try:
            files = _write_once(self.libraries, shipped_dir())
        except OSError:                     # no writable temporary directory: compile here as before
            return 0
        for key, digest in self.keys.items():
            _INSTALLED[key] = files[digest]
        _BUNDLES.add(self.digest)
        return len(self.keys)


def _write_once(libraries: dict, directory: Path) -> dict:
    """Digest -> file of each library, written unless a file of that name (its content's hash) exists."""
    directory.mkdir(parents=True, exist_ok=True)
    files = {}
    for digest, data in libraries.items():
        path = files[digest] = directory / f"bc_{digest}.so"
        if not path.exists():
            fd, tmp = tempfile.mkstemp(dir=directory, prefix=".ship-")
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
            os.replace(tmp, path)           # atomic: a concurrent worker never loads half a file
    return files


@dataclass
class Recording:
    """Libraries handed out while it was open: lookup key -> file (see :func:`recording`)."""

    libraries: dict = field(default_factory=dict)

    def bundle(self) -> KernelBundle:
        """The recorded libraries, read into a :class:`KernelBundle`."""
        blobs, keys = {}, {}
        for key, path in self.libraries.items():
            data = Path(path).read_bytes()
            digest = hashlib.sha256(data).hexdigest()[:40]
            blobs[digest] = data
            keys[key] = digest
        return KernelBundle(blobs, keys)


@contextmanager
def recording():
    """Note every library built or loaded inside the ``with`` block.

    Examples
    --------
    >>> from bondgraph.numerics import c_shipped
    >>> with c_shipped.recording() as rec:
    ...     pass                          # simulate, build a UKF, ...
    >>> rec.bundle().nbytes
    0
    """
    rec = Recording()
    _RECORDINGS.append(rec)
    try:
        yield rec
    finally:
        _RECORDINGS.remove(rec)
