"""The sub-step loop of :func:`bondgraph.numerics.evaluate_stiff.rosenbrock_samples` in C.

The Rosenbrock W-method evaluates :math:`J` and :math:`W^{-1}` once per sample interval, then
takes up to thousands of sub-steps with them.  In Python each sub-step costs four calls of
``CompiledModel.f`` (argument normalisation included) and four batched matrix products (two of
each took about 40 us on the exoskeleton), where the model's generated ``bc_f`` takes about 1 us.  This driver
runs the sub-steps of one interval in C, calling the model's ``bc_f`` (the C contract of
:mod:`bondgraph.numerics.codegen_c`) through a function pointer, so, as the RK4 sample driver of
:mod:`bondgraph.numerics.evaluate_samples_c`, it is compiled once per machine and the model's
source is unchanged.  The numbers are those of the Python loop up to the order of the sums in
the matrix products (tested in ``tests/test_numerics_stiff.py``).

Only models without algebraic loops use it: their ``f`` needs no Newton solve between stages.
"""
from __future__ import annotations

import ctypes

__all__ = ["STEPS_SOURCE", "steps_driver", "c_derivative"]

STEPS_SOURCE = r"""
#include <math.h>
#include <stddef.h>
typedef void (*bc_f_fn)(int n, const double *t, int st, const double *x, const double *u, int su,
                        const double *z, const double *d, int sd, const double *p, int sp,
                        double step, double *out);

/* out = W x for each of the n rows: W (n, nx, nx), x and out (n, nx). */
static void bc_rows_product(int n, int nx, const double *W, const double *x, double *out) {
  for (int r = 0; r < n; ++r) {
    const double *Wr = W + (size_t)r * nx * nx, *xr = x + (size_t)r * nx;
    double *o = out + (size_t)r * nx;
    for (int i = 0; i < nx; ++i) {
      double acc = 0.0;
      for (int j = 0; j < nx; ++j) acc += Wr[(size_t)i * nx + j] * xr[j];
      o[i] = acc;
    }
  }
}

/* m Rosenbrock W sub-steps of length h from t0 on the n rows of x (n, nx), in place, in the
   increments u_i of an s-stage method (bondgraph.numerics.evaluate_stiff):
     u_i = Winv (gamma h f(x + sum_{j<i} a_ij u_j) + sum_{j<i} c_ij u_j),  x += sum_i mw_i u_i,
   a and c (s, s) row-major, Winv (n, nx, nx) each row's W^-1.  The inputs u are one row shared by
   the batch; d and p have row strides sd, sp (0: one row shared); z is the (empty) algebraic vector.
   Every stage sees the time at the sub-step's start.  work holds (2 + s) n nx doubles.
   Returns the largest |sum_i me_i u_i| / tol[k] over the sub-steps, rows and states k (the local
   error estimate against its tolerance; tol[k] = inf: not measured), NaN where one is NaN. */
double bc_rosw_steps(void *fn, int n, int nx, double t0, double h, int m, int s, const double *a,
                     const double *c, const double *mw, const double *me, const double *tol, double gamma,
                     double *x, const double *u, const double *z, const double *d, int sd, const double *p,
                     int sp, const double *Winv, double *work) {
  bc_f_fn f = (bc_f_fn)fn;
  size_t nn = (size_t)n * nx;
  double *fv = work, *xs = work + nn, *stage = work + 2 * nn;
  double t = t0, worst = 0.0;
  int nan = 0;
  for (int step = 0; step < m; ++step) {
    for (int i = 0; i < s; ++i) {
      for (size_t q = 0; q < nn; ++q) xs[q] = x[q];
      for (int j = 0; j < i; ++j) {
        const double aij = a[i * s + j], *uj = stage + (size_t)j * nn;
        if (aij != 0.0) for (size_t q = 0; q < nn; ++q) xs[q] += aij * uj[q];
      }
      f(n, &t, 0, xs, u, 0, z, d, sd, p, sp, 0.0, fv);
      for (size_t q = 0; q < nn; ++q) fv[q] *= gamma * h;
      for (int j = 0; j < i; ++j) {
        const double cij = c[i * s + j], *uj = stage + (size_t)j * nn;
        if (cij != 0.0) for (size_t q = 0; q < nn; ++q) fv[q] += cij * uj[q];
      }
      bc_rows_product(n, nx, Winv, fv, stage + (size_t)i * nn);
    }
    for (int i = 0; i < s; ++i) {
      const double *ui = stage + (size_t)i * nn;
      for (size_t q = 0; q < nn; ++q) x[q] += mw[i] * ui[q];
    }
    for (size_t q = 0; q < nn; ++q) {
      double e = 0.0;
      for (int i = 0; i < s; ++i) e += me[i] * stage[(size_t)i * nn + q];
      e = fabs(e) / tol[q % (size_t)nx];
      if (e != e) nan = 1;
      else if (e > worst) worst = e;
    }
    t += h;
  }
  return nan ? NAN : worst;
}
"""


def steps_driver():
    """The compiled ``bc_rosw_steps`` (ctypes function), or None without a C compiler."""
    from .c_build import driver_function
    vp, i, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    return driver_function(STEPS_SOURCE, "bc_rosw_steps",
                           [vp, i, i, dbl, dbl, i, i, vp, vp, vp, vp, vp, dbl, vp, vp, vp, vp, i, vp, i, vp, vp], dbl)


def c_derivative(model):
    """The address of `model`'s generated ``bc_f`` when the C sub-step loop can run it: the C
    backend, no algebraic loops, and a driver compiled; else None."""
    if model.backend != "c" or model.algebraic_names or steps_driver() is None:
        return None
    main = getattr(getattr(model, "_k", None), "_main", None)
    fn = getattr(main, "f", None)
    return None if fn is None else ctypes.cast(fn, ctypes.c_void_p).value
