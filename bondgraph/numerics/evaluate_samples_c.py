"""The sample loop of :func:`bondgraph.numerics.evaluate_samples.rk4_samples` in C.

A model's ``bc_rk4_every`` (``bc_rk4`` of the C contract of :mod:`bondgraph.numerics.codegen_c`
with the held values updated at every `every`-th sub-step) integrates one sample interval;
called from Python once per sample, the call and the copies of the states
into the result cost about 3 us per sample on pam, more than the integration itself (about
2 us for 4 RK4 sub-steps).  This driver makes the same calls, with the same arguments in the
same order, from a C loop: the numbers are bit for bit those of the Python loop (tested in
``tests/test_diagnosis_residuals.py``).

The driver does not depend on the model: it receives ``bc_rk4_every`` as a function pointer, so it
is compiled once per machine (:func:`bondgraph.numerics.c_build.compile_source`, cached) and
the model's generated source, its FMU export included, is unchanged.
"""
from __future__ import annotations

import ctypes

__all__ = ["DRIVER_SOURCE", "sample_driver", "run_samples"]

DRIVER_SOURCE = r"""
#include <string.h>
typedef int (*bc_rk4_every_fn)(int n, double t0, double h, int m, int every, double *x, const double *u,
                               int su, double *z, const double *zinit, double *d, const double *p, int sp,
                               int *status);

/* The loop over the nt - 1 sample intervals of t: bc_rk4_every on interval k with the inputs
   of row k (shared by the n batch rows: stride 0), then the states and held values copied
   into row k + 1 of X (nt, n, nx) and D (nt, n, nd).  Returns nt - 1 when every interval
   was integrated, -1 when bc_rk4_every ran out of memory, or the index k of the interval after
   which, with check set, some status is nonzero (a Newton failure; x, d are then as
   bc_rk4_every left them). */
int bc_rk4_samples(void *fn, int every, int n, int nt, const double *t, const double *hs, const int *ms,
                   const double *U, int nu, double *x, int nx, double *z, const double *zinit,
                   double *d, int nd, const double *p, int sp, int *status, int check,
                   double *X, double *D) {
  bc_rk4_every_fn rk4 = (bc_rk4_every_fn)fn;
  size_t xs = (size_t)n * nx, ds = (size_t)n * nd;
  for (int k = 0; k < nt - 1; ++k) {
    if (rk4(n, t[k], hs[k], ms[k], every, x, U + (size_t)k * nu, 0, z, zinit, d, p, sp, status) < 0)
      return -1;
    if (check) {
      int bad = 0;
      for (int i = 0; i < n; ++i) bad |= status[i];
      if (bad) return k;
    }
    memcpy(X + (size_t)(k + 1) * xs, x, sizeof(double) * xs);
    memcpy(D + (size_t)(k + 1) * ds, d, sizeof(double) * ds);
  }
  return nt - 1;
}
"""


def sample_driver():
    """The compiled ``bc_rk4_samples`` (ctypes function), or None without a C compiler."""
    from .c_build import driver_function
    vp, i = ctypes.c_void_p, ctypes.c_int
    return driver_function(DRIVER_SOURCE, "bc_rk4_samples",
                           [vp, i, i, i, vp, vp, vp, vp, i, vp, i, vp, vp, vp, i, vp, i, vp, i, vp, vp], i)


def run_samples(driver, rk4, t, hs, ms, U, x, z, zinit, d, p, sp, status, check, X, D, every: int = 1) -> int:
    """Call `driver` on C-contiguous float64 arrays (int32 `ms`, `status`), held values updated at
    every `every`-th sub-step; its return value."""
    ptr = ctypes.cast(rk4, ctypes.c_void_p).value
    n, nx = x.shape
    nd = d.shape[1]
    return driver(ptr, int(every), n, t.size, t.ctypes.data, hs.ctypes.data, ms.ctypes.data, U.ctypes.data,
                  U.shape[1], x.ctypes.data, nx, z.ctypes.data, zinit.ctypes.data, d.ctypes.data, nd, p.ctypes.data,
                  sp, status.ctypes.data, int(check), X.ctypes.data, D.ctypes.data)
