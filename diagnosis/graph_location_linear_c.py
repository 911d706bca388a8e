"""The propagation loop of :meth:`diagnosis.graph_location_linear.LinearisedResponse.response` in C.

The loop runs once per sample over the whole training part (91 000 samples on 130 s of pam at
1 kHz) and does a few small matrix products per sample; from Python each sample costs about
10 us of call overhead, 2 s per response and 8 s of a pam diagnosis.  This kernel does the same
products in a C loop.  Two savings on top:

* the columns are sequences chosen from a *base* matrix (``columns``), so a basis shared by
  several places (the location's hat functions, one block per junction) is stored once;
* a sequence that is zero up to sample k leaves its response zero up to k (``dx_0 = 0``), so
  the columns are taken in the order in which their sequences start and only those started
  are propagated (a hat function starts at its knot: about half the work on a hat basis).

It does not depend on the model, so it is compiled once per machine
(:func:`bondgraph.numerics.c_build.driver_function`); without a compiler the caller keeps its
numpy loop, and the two agree to rounding (``tests/test_diagnosis_graph_location.py``).
"""
from __future__ import annotations

import ctypes

import numpy as np

__all__ = ["RESPONSE_SOURCE", "propagate"]

RESPONSE_SOURCE = r"""
#include <string.h>
#pragma GCC optimize("tree-vectorize")
/* Linear time-varying response of m perturbation sequences (row-major arrays):
     dy_k = C_k dx_k + D_k[:, channel] * s_k          at the kept rows k = rows[r]
     dx_{k+1} = Phi_k dx_k + Gamma_k[:, channel] * s_k,  dx_0 = 0,
   where column c's sequence is s_k = base[k, column[c]].  Phi (n-1, nx, nx), Gamma (n-1, nx, nc),
   C (n, ny, nx), D (n, ny, nc), channel and column (m), base (n, mb), rows (n_rows, increasing),
   first (m, non-decreasing): column c's sequence is zero before sample first[c], so at sample k
   only the columns c < (number with first <= k) are propagated.  dx and work (nx, m); out
   (n_rows, ny, m) must be zero on entry.  The sums over j run in the order of a dot product, the
   loops over the columns innermost. */
void bc_ltv_response(int n, int nx, int ny, int nc, int m, int mb, const double *Phi,
                     const double *Gamma, const double *C, const double *D, const int *channel,
                     const int *column, const double *base, const int *first, const int *rows,
                     int n_rows, double *dx, double *work, double *s, double *out) {
  int r = 0, na = 0;
  memset(dx, 0, sizeof(double) * (size_t)nx * m);
  for (int k = 0; k < n; ++k) {
    while (na < m && first[na] <= k) ++na;
    const double *b = base + (size_t)k * mb;
    for (int c = 0; c < na; ++c) s[c] = b[column[c]];
    if (r < n_rows && rows[r] == k) {
      const double *Ck = C + (size_t)k * ny * nx, *Dk = D + (size_t)k * ny * nc;
      for (int i = 0; i < ny; ++i) {
        double *restrict o = out + ((size_t)r * ny + i) * m;
        for (int c = 0; c < na; ++c) o[c] = Dk[i * nc + channel[c]] * s[c];
        for (int j = 0; j < nx; ++j) {
          const double a = Ck[i * nx + j], *restrict dj = dx + (size_t)j * m;
          for (int c = 0; c < na; ++c) o[c] += a * dj[c];
        }
      }
      ++r;
    }
    if (k < n - 1 && nx) {
      const double *P = Phi + (size_t)k * nx * nx, *G = Gamma + (size_t)k * nx * nc;
      for (int i = 0; i < nx; ++i) {
        double *restrict w = work + (size_t)i * m;
        for (int c = 0; c < na; ++c) w[c] = G[i * nc + channel[c]] * s[c];
        for (int j = 0; j < nx; ++j) {
          const double a = P[i * nx + j], *restrict dj = dx + (size_t)j * m;
          for (int c = 0; c < na; ++c) w[c] += a * dj[c];
        }
      }
      for (int i = 0; i < nx; ++i) memcpy(dx + (size_t)i * m, work + (size_t)i * m, sizeof(double) * na);
    }
  }
}

/* first[c]: the first sample k at which base[k, c] is nonzero, n if none (base (n, mb)). */
void bc_first_nonzero(int n, int mb, const double *base, int *first) {
  int left = mb;
  for (int c = 0; c < mb; ++c) first[c] = n;
  for (int k = 0; k < n && left > 0; ++k) {
    const double *b = base + (size_t)k * mb;
    for (int c = 0; c < mb; ++c)
      if (first[c] == n && b[c] != 0.0) { first[c] = k; --left; }
  }
}
"""


def _kernels():
    """``(bc_ltv_response, bc_first_nonzero)``, or None without a C compiler."""
    from bondgraph.numerics.c_build import driver_function
    vp, i = ctypes.c_void_p, ctypes.c_int
    response = driver_function(RESPONSE_SOURCE, "bc_ltv_response",
                               [i, i, i, i, i, i, vp, vp, vp, vp, vp, vp, vp, vp, vp, i, vp, vp, vp, vp], None)
    first = driver_function(RESPONSE_SOURCE, "bc_first_nonzero", [i, i, vp, vp], None)
    return None if response is None or first is None else (response, first)


def propagate(Phi, Gamma, C, D, channel, base, columns, rows):
    """``out (n_rows, ny, m)`` of the recursion above, or None without a C compiler.

    Column c of the result is the response to ``base[:, columns[c]]`` entering on input
    ``channel[c]``.  `rows` must be strictly increasing sample indices (the caller checks)."""
    kernels = _kernels()
    if kernels is None:
        return None
    fn, first_nonzero = kernels
    base = np.ascontiguousarray(base, dtype=float)
    n, mb = base.shape
    columns = np.asarray(columns, dtype=int)
    m = columns.size
    nx, ny, nc = C.shape[2], C.shape[1], D.shape[2]
    starts = np.empty(mb, dtype=np.intc)                 # per base column
    first_nonzero(n, mb, base.ctypes.data, starts.ctypes.data)
    order = np.argsort(starts[columns], kind="stable")
    Phi, Gamma, C, D = (np.ascontiguousarray(a, dtype=float) for a in (Phi, Gamma, C, D))
    channel_o = np.ascontiguousarray(np.asarray(channel)[order], dtype=np.intc)
    column_o = np.ascontiguousarray(columns[order], dtype=np.intc)
    first = np.ascontiguousarray(starts[columns][order], dtype=np.intc)
    rows = np.ascontiguousarray(rows, dtype=np.intc)
    dx, work, s = np.empty((nx, m)), np.empty((nx, m)), np.empty(m)
    out = np.zeros((rows.size, ny, m))
    fn(n, nx, ny, nc, m, mb, Phi.ctypes.data, Gamma.ctypes.data, C.ctypes.data, D.ctypes.data,
       channel_o.ctypes.data, column_o.ctypes.data, base.ctypes.data, first.ctypes.data, rows.ctypes.data,
       rows.size, dx.ctypes.data, work.ctypes.data, s.ctypes.data, out.ctypes.data)
    result = np.empty_like(out)
    result[:, :, order] = out
    return result
