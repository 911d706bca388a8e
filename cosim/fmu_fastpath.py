"""One C call per communication step for an FMU without direct feedthrough.

Every ctypes call from Python costs about a microsecond, so the three FMI calls
of a step (set inputs, ``doStep``, get outputs) cost three.  For an FMU whose
outputs do not depend on its inputs at the same instant, the outputs at
:math:`t + \\Delta t` are known as soon as ``doStep`` returns, so a tiny C
function makes the three calls through the FMU's own function pointers in one
go.  It is compiled once per machine (cached like the model kernels, see
:func:`bondgraph.numerics.c_build.compile_source`); without a C compiler
:func:`advance_function` returns None and the component makes the three calls.
"""
from __future__ import annotations

import ctypes
import functools
from ctypes import c_double, c_int, c_size_t, c_void_p

__all__ = ["advance_function", "WHICH"]

#: Which call a failing status came from.
WHICH = {0: "set inputs", 1: "doStep", 2: "get outputs", 3: "doStep (terminateSimulation)"}

_SOURCE = r"""
/* bondcosim co-simulation fast path: set inputs, doStep, get outputs. */
#include <stdbool.h>
#include <stddef.h>

typedef int (*set2_t)(void *, const unsigned *, size_t, const double *);
typedef int (*get2_t)(void *, const unsigned *, size_t, double *);
typedef int (*step2_t)(void *, double, double, int);
typedef int (*set3_t)(void *, const unsigned *, size_t, const double *, size_t);
typedef int (*get3_t)(void *, const unsigned *, size_t, double *, size_t);
typedef int (*step3_t)(void *, double, double, bool, bool *, bool *, bool *, double *);

/* Returns the first status above fmi2Warning (1) and sets *which (0 set, 1 doStep,
   2 get); 0 when every call succeeded. */
int bc_advance2(void *set, void *step, void *get, void *c,
                const unsigned *vin, size_t nin, const double *u,
                const unsigned *vout, size_t nout, double *y, int *which,
                double t, double dt) {
  int s;
  if (nin && (s = ((set2_t)set)(c, vin, nin, u)) > 1) { *which = 0; return s; }
  if ((s = ((step2_t)step)(c, t, dt, 0)) > 1) { *which = 1; return s; }
  if (nout && (s = ((get2_t)get)(c, vout, nout, y)) > 1) { *which = 2; return s; }
  return 0;
}

/* FMI 3.0: as above; a request to terminate is reported as *which = 3, status 3. */
int bc_advance3(void *set, void *step, void *get, void *c,
                const unsigned *vin, size_t nin, const double *u,
                const unsigned *vout, size_t nout, double *y, int *which,
                double t, double dt) {
  int s;
  bool event = false, terminate = false, early = false;
  double last = t;
  if (nin && (s = ((set3_t)set)(c, vin, nin, u, nin)) > 1) { *which = 0; return s; }
  if ((s = ((step3_t)step)(c, t, dt, false, &event, &terminate, &early, &last)) > 1) {
    *which = 1; return s;
  }
  if (terminate) { *which = 3; return 3; }
  if (nout && (s = ((get3_t)get)(c, vout, nout, y, nout)) > 1) { *which = 2; return s; }
  return 0;
}
"""


def _library():
    """The bridge library, or None without a compiler; noted for a sweep's shipping on every call
    (:mod:`bondgraph.numerics.c_shipped`: loaded once per process, it must still be recorded each time)."""
    from bondgraph.numerics import c_shipped
    from bondgraph.numerics.c_build import source_key
    lib, path = _load()
    if lib is not None:
        c_shipped.note(source_key(_SOURCE), path)
    return lib


@functools.cache
def _load():
    from bondgraph.numerics.c_build import compile_source
    from cosim.errors import CompilationError
    try:
        path = compile_source(_SOURCE)
        lib = ctypes.CDLL(str(path))
    except CompilationError:
        return None, None
    for name in ("bc_advance2", "bc_advance3"):
        fn = getattr(lib, name)
        fn.argtypes = [c_void_p] * 5 + [c_size_t, c_void_p, c_void_p, c_size_t, c_void_p,
                                        c_void_p, c_double, c_double]
        fn.restype = c_int
    return lib, path


def _address(function) -> int:
    return ctypes.cast(function, c_void_p).value


def advance_function(dll, component: int, version: int, vr_in, n_in: int, u_ptr, vr_out,
                     n_out: int, y_ptr, which: c_int):
    """``f(t, dt) -> status``: set inputs, ``doStep(t, dt)``, get outputs, in one C call.

    Parameters
    ----------
    dll : ctypes.CDLL
        The FMU's loaded library (fmpy's ``fmu.dll``).
    component : int
        The FMU instance pointer.
    version : {2, 3}
    vr_in, vr_out : ctypes arrays of c_uint
        Value references of the inputs and outputs.
    n_in, n_out : int
    u_ptr, y_ptr : ctypes pointers
        Input values (read) and output values (written).
    which : ctypes.c_int
        Receives which call failed (see :data:`WHICH`).

    Returns
    -------
    callable or None
        None when no C compiler is available.
    """
    lib = _library()
    if lib is None:
        return None
    names = (("fmi2SetReal", "fmi2DoStep", "fmi2GetReal") if version == 2 else
             ("fmi3SetFloat64", "fmi3DoStep", "fmi3GetFloat64"))
    pointers = [c_void_p(_address(getattr(dll, n))) for n in names]
    fn = lib.bc_advance2 if version == 2 else lib.bc_advance3
    return functools.partial(fn, *pointers, c_void_p(component),
                             ctypes.cast(vr_in, c_void_p), n_in, ctypes.cast(u_ptr, c_void_p),
                             ctypes.cast(vr_out, c_void_p), n_out, ctypes.cast(y_ptr, c_void_p),
                             ctypes.byref(which))
