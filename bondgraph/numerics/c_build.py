"""Compiling, caching and loading the generated C of :mod:`bondgraph.numerics.codegen_c`.

:func:`compile_source` turns a C translation unit into a shared library with
the system compiler (:func:`find_compiler`), cached in :func:`cache_dir` by the
sha256 of source, compiler and flags; :func:`build_library` generates
(:func:`bondgraph.numerics.codegen_c.generate_source`), compiles and loads one library
of a :class:`~bondgraph.system.StateEquations`, skipping generation too when
the same equations were built before (an index file ``idx_<key>`` in the cache
maps a hash of the equations to the library); :class:`CLibrary` is the 1:1
ctypes binding of the functions of the C contract documented in
:mod:`bondgraph.numerics.codegen_c`, which re-exports every name of this module.

Libraries shipped from another process (:mod:`bondgraph.numerics.c_shipped`: a sweep's
client to its workers) come first: both :func:`compile_source` and
:func:`build_library` look up their compiler-independent key there before
they need a compiler, and note what they hand out for an open recording.

Compiler flags
--------------
:data:`CFLAGS`.  The SLP vectoriser is switched off
(``-fno-tree-slp-vectorize``): on straight-line generated code it dominated
compile time and gains nothing.
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import weakref
from pathlib import Path

import sympy as sp

from . import c_shipped, codegen_c
from .codegen_c import PARTS, generate_source
from ..errors import CompilationError

__all__ = ["compile_source", "driver_function", "build_library", "find_compiler", "c_available", "cache_dir", "source_key",
           "equations_key", "CLibrary", "CFLAGS"]

#: Compiler flags (besides ``-o``, source and ``-lm``).
CFLAGS = ("-O2", "-fno-tree-slp-vectorize", "-shared", "-fPIC")


def find_compiler() -> str | None:
    """Path of the C compiler: ``$CC`` if set, else the first of cc, gcc, clang on PATH."""
    for name in ([os.environ["CC"]] if os.environ.get("CC") else []) + ["cc", "gcc", "clang"]:
        path = shutil.which(name)
        if path:
            return path
    return None


def c_available() -> bool:
    """True when C kernels can be had here: a compiler is found, or libraries were shipped in
    (:mod:`bondgraph.numerics.c_shipped`), so that ``backend="auto"`` picks C as the shipping process did."""
    return find_compiler() is not None or bool(c_shipped.installed())


def source_key(source: str) -> str:
    """Compiler-independent lookup key of a library of C `source` (:mod:`bondgraph.numerics.c_shipped`)."""
    return "src:" + hashlib.sha256("\0".join([source, *CFLAGS]).encode()).hexdigest()[:40]


def cache_dir() -> Path:
    """Directory of compiled libraries: ``$BONDCOSIM_CACHE``, else ``~/.cache/bondcosim``."""
    env = os.environ.get("BONDCOSIM_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "bondcosim"


def compile_source(source: str, *, compiler: str | None = None) -> Path:
    """Compile C source to a shared library, or reuse the cached one.

    The library is ``<cache>/bc_<sha256>.so``, where the hash covers the
    source, compiler path and flags.  It is built in a temporary file of the
    cache directory and renamed into place (atomic on POSIX), so concurrent
    processes compiling the same model never load a half-written file.

    Parameters
    ----------
    source : str
        C translation unit.
    compiler : str, optional
        Compiler executable; default :func:`find_compiler`.

    Returns
    -------
    pathlib.Path
        Path of the shared library.

    Raises
    ------
    CompilationError
        No compiler found, or it failed (its output is in ``.output``).
    """
    shipped = c_shipped.lookup(source_key(source))
    if shipped is not None:
        c_shipped.note(source_key(source), shipped)
        return shipped
    compiler = compiler or find_compiler()
    if compiler is None:
        raise CompilationError("no C compiler found: set $CC or put cc/gcc/clang on PATH "
                               "(or use backend='numpy')")
    key = hashlib.sha256("\0".join([source, compiler, *CFLAGS]).encode()).hexdigest()
    directory = cache_dir()
    target = directory / f"bc_{key[:40]}.so"
    if not target.exists():
        _compile(source, compiler, key, target)
    c_shipped.note(source_key(source), target)
    return target


_DRIVERS: dict = {}   # (source key, name) -> loaded function, or None (no compiler)


def driver_function(source: str, name: str, argtypes, restype):
    """Function `name` of the model-independent C `source` (a sample-loop driver), compiled
    once per machine (:func:`compile_source`) and loaded once per process; None when no
    compiler can build it (the caller then keeps its Python loop)."""
    key = (source_key(source), name)
    if key not in _DRIVERS:
        try:
            fn = getattr(ctypes.CDLL(str(compile_source(source))), name)
        except (CompilationError, OSError):
            fn = None
        if fn is not None:
            fn.argtypes, fn.restype = list(argtypes), restype
        _DRIVERS[key] = fn
    return _DRIVERS[key]


def _compile(source: str, compiler: str, key: str, target: Path) -> None:
    """Compile `source` into `target` through a temporary directory next to it."""
    directory = target.parent
    directory.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=directory, prefix=".build-") as tmp:
        src = Path(tmp) / f"bc_{key[:40]}.c"
        src.write_text(source)
        lib = Path(tmp) / "lib.so"
        _run_compiler([compiler, *CFLAGS, "-o", str(lib), str(src), "-lm"])
        os.replace(src, directory / src.name)   # keep the source next to the library
        os.replace(lib, target)


def _run_compiler(cmd: list) -> None:
    """Run one compiler command; CompilationError with its output if it fails."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise CompilationError(f"could not run {' '.join(cmd)}: {exc}") from None
    if proc.returncode != 0:
        raise CompilationError(f"C compiler failed (exit {proc.returncode}): {' '.join(cmd)}",
                               output=(proc.stdout + proc.stderr).strip())


_EQUATIONS_KEYS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def equations_key(eqs, part: str = "main") -> str:
    """Compiler-independent lookup key of the `part` library of `eqs` (:mod:`bondgraph.numerics.c_shipped`).

    A sha256 of everything the generated source depends on: no code is generated
    (no cse); each distinct expression node is digested once (:func:`_tree_digest`),
    and the key is kept per equations object.
    """
    keys = _EQUATIONS_KEYS.setdefault(eqs, {})
    if part not in keys:
        keys[part] = "eqs:" + _equations_hash(eqs, part)[:40]
    return keys[part]


def _equations_hash(eqs, part: str) -> str:
    memo: dict = {}
    digest = lambda e: _tree_digest(e, memo)    # noqa: E731
    parts = [codegen_c.GENERATOR_VERSION, part, *CFLAGS, str(codegen_c.SPLIT_STATEMENTS), eqs.name]
    for field in ("t", "step"):
        parts.append(digest(getattr(eqs, field)))
    for field in ("states", "inputs", "params", "algebraic", "held",
                  "f", "h", "residuals", "held_update", "f_short", "h_short", "held_update_short"):
        parts.append("|".join(digest(e) for e in getattr(eqs, field)))
    parts.append("|".join(f"{digest(s)}={digest(e)}" for s, e in eqs.assignments))
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def _tree_digest(expr, memo: dict) -> str:
    """A digest of `expr`'s tree: class name and the digests of its arguments, leaves by ``srepr``
    (a symbol with its assumptions, a number with its precision): what ``srepr`` prints, but
    each shared subexpression (the equations' assignments reach every right-hand side) is
    visited once per object, and no terms are re-sorted for printing: about 15 times faster
    than ``srepr`` on pam.  Sympy keeps the arguments of Add and Mul in a canonical order
    (``Basic.compare``), so the digest does not depend on the process."""
    key = id(expr)
    found = memo.get(key)
    if found is not None:
        return found[0]
    if not isinstance(expr, sp.Basic):
        text = f"{type(expr).__name__}:{expr!r}"
    elif not expr.args:
        text = sp.srepr(expr)
    else:
        text = type(expr).__name__ + "(" + ",".join(_tree_digest(a, memo) for a in expr.args) + ")"
    digest = hashlib.blake2b(text.encode(), digest_size=16).hexdigest()
    memo[key] = (digest, expr)      # the object is kept so that its id is not reused meanwhile
    return digest


def build_library(eqs, *, part: str = "main") -> "CLibrary":
    """Generate, compile (or reuse) and load one library of `eqs`.

    A library shipped in (:mod:`bondgraph.numerics.c_shipped`) under
    :func:`equations_key` is loaded as it is.  Otherwise a small index file
    ``idx_<key>`` in the cache maps a hash of the equations themselves (and
    the compiler) to the library, so a later process skips code generation as
    well as compilation.

    Parameters
    ----------
    eqs : StateEquations
    part : {"main", "jacobian"}
        See :func:`bondgraph.numerics.codegen_c.generate_source`.

    Returns
    -------
    CLibrary

    Raises
    ------
    CompilationError
        No compiler, or it failed.
    """
    key = equations_key(eqs, part)
    path = c_shipped.lookup(key) or _cached_library(eqs, part, key)
    c_shipped.note(key, path)
    return CLibrary(path)


def _cached_library(eqs, part: str, key: str) -> Path:
    """The library through the index file of `key` and this compiler, compiling if need be."""
    compiler = find_compiler()
    if compiler is None:
        raise CompilationError("no C compiler found: set $CC or put cc/gcc/clang on PATH "
                               "(or use backend='numpy')")
    index = cache_dir() / f"idx_{hashlib.sha256((key + chr(0) + compiler).encode()).hexdigest()[:40]}"
    try:
        cached = cache_dir() / index.read_text().strip()
        if cached.exists():
            return cached
    except OSError:
        pass
    path = compile_source(generate_source(eqs, part=part), compiler=compiler)
    fd, tmp = tempfile.mkstemp(dir=index.parent, prefix=".idx-")
    with os.fdopen(fd, "w") as fh:
        fh.write(path.name)
    os.replace(tmp, index)
    return path


class CLibrary:
    """1:1 ctypes binding of a library made by :func:`bondgraph.numerics.codegen_c.generate_source`.

    Attributes
    ----------
    path : pathlib.Path
    dims : dict str -> int
        ``NX NU NP NZ ND NY``.
    kernels : list of str
        Names of the ``bc_*`` functions the library holds; each is an attribute
        (``lib.f``, ``lib.jac_fx``, ``lib.solve``...) taking ``int``,
        ``c_void_p`` and ``double`` arguments as in the C contract of
        :mod:`bondgraph.numerics.codegen_c`.
        ``solve`` returns the number of failed rows.
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        self._dll = ctypes.CDLL(str(self.path))
        dims = (ctypes.c_int * 6)()
        self._dll.bc_dims(dims)
        self.dims = dict(zip(("NX", "NU", "NP", "NZ", "ND", "NY"), list(dims)))
        vp, i, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
        batch = [i, vp, i, vp, vp, i, vp, vp, i, vp, i, dbl]
        self.kernels = []
        for name in (*PARTS["main"], *PARTS["jacobian"], "solve"):
            try:
                fn = getattr(self._dll, f"bc_{name}")
            except AttributeError:
                continue
            fn.argtypes = batch + [vp]
            fn.restype = ctypes.c_int if name == "solve" else None
            setattr(self, name, fn)
            self.kernels.append(name)
        if hasattr(self._dll, "bc_rk4_every"):   # bc_rk4 (the FMU's entry) is it with every = 1
            self.rk4 = self._dll.bc_rk4_every
            self.rk4.argtypes = [i, dbl, dbl, i, i, vp, vp, i, vp, vp, vp, vp, i, vp]
            self.rk4.restype = ctypes.c_int
            self.kernels.append("rk4")
