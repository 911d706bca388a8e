"""C backend of :func:`bondgraph.numerics.evaluate.compile_model`: kernels in compiled libraries.

:class:`CKernels` implements the kernel interface of :mod:`bondgraph.numerics.evaluate`
on the shared libraries of :func:`bondgraph.numerics.c_build.build_library`: the
``"main"`` library (``f``, ``h``, ``held_update``, ``residuals``, ``jac_rz``,
``bc_solve``, ``bc_rk4``) is built at construction, the ``"jacobian"`` one
(``jac_fx``, ``jac_fz``, ``jac_rx``) on first use.  Arrays are passed by pointer
with the strides of the C contract in :mod:`bondgraph.numerics.codegen_c`.
"""
from __future__ import annotations

import numpy as np

from .c_build import build_library
from .codegen_c import PARTS

__all__ = ["CKernels"]


def _stride(a: np.ndarray, n: int) -> int:
    """C stride of a broadcastable array: 0 when one row is shared by n > 1 rows."""
    return 0 if a.shape[0] == 1 and n != 1 else (a.shape[1] if a.ndim == 2 else 1)


class CKernels:
    """Kernels of `eqs` in generated C libraries (the interface of :mod:`bondgraph.numerics.evaluate`).

    Parameters
    ----------
    eqs : StateEquations

    Raises
    ------
    CompilationError
        No C compiler, or it failed.
    """

    backend = "c"

    def __init__(self, eqs):
        self._eqs = eqs
        self._main = build_library(eqs, part="main")
        self._jac = None

    def note_libraries(self) -> None:
        """Tell an open :func:`bondgraph.numerics.c_shipped.recording` which libraries these kernels use."""
        from . import c_shipped
        from .c_build import equations_key
        if not c_shipped.recording_open():
            return
        for part, lib in (("main", self._main), ("jacobian", self._jac)):
            if lib is not None:
                c_shipped.note(equations_key(self._eqs, part), lib.path)

    def _lib(self, name):
        if name in PARTS["jacobian"]:
            if self._jac is None:
                self._jac = build_library(self._eqs, part="jacobian")
            return self._jac
        return self._main

    @staticmethod
    def _args(t, x, u, z, d, p, step):
        n = x.shape[0]
        return (n, t.ctypes.data, _stride(t, n), x.ctypes.data, u.ctypes.data, _stride(u, n),
                z.ctypes.data, d.ctypes.data, _stride(d, n), p.ctypes.data, _stride(p, n),
                float(step))

    def call(self, name, t, x, u, z, d, p, step, out):
        getattr(self._lib(name), name)(*self._args(t, x, u, z, d, p, step), out.ctypes.data)

    def solve(self, t, x, u, z, d, p):
        status = np.zeros(x.shape[0], dtype=np.intc)
        self._main.solve(*self._args(t, x, u, z, d, p, 0.0), status.ctypes.data)
        return status

    def rk4(self, t0, h, m, x, u, z, zinit, d, p, every=1):
        n = x.shape[0]
        status = np.zeros(n, dtype=np.intc)
        if self._main.rk4(n, t0, h, m, int(every), x.ctypes.data, u.ctypes.data, _stride(u, n), z.ctypes.data,
                          zinit.ctypes.data, d.ctypes.data, p.ctypes.data, _stride(p, n), status.ctypes.data) < 0:
            raise MemoryError("bc_rk4: out of memory")
        return status
