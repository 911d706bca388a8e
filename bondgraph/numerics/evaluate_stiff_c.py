"""The sub-step loop of :func:`bondgraph.numerics.evaluate_stiff.ros2_samples` in C.

ROS2 evaluates :math:`J` and :math:`W^{-1}` once per sample interval, then takes up to
thousands of sub-steps with them.  In Python each sub-step costs two calls of
``CompiledModel.f`` (argument normalisation included) and two batched matrix products, about
40 us on the exoskeleton, where the model's generated ``bc_f`` takes about 1 us.  This driver
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

/* m ROS2 sub-steps of length h from t0 on the n rows of x (n, nx), in place:
     W k1 = f(x),  W k2 = f(x + h k1) - 2 k1,  x += 3/2 h k1 + 1/2 h k2,
   with Winv (n, nx, nx) each row's W^-1.  The inputs u are one row shared by the batch; d and
   p have row strides sd, sp (0: one row shared); z is the (empty) algebraic vector.  Both
   stages see the time at the sub-step's start.  work holds 4 n nx doubles. */
void bc_ros2_steps(void *fn, int n, int nx, double t0, double h, int m, double *x, const double *u,
                   const double *z, const double *d, int sd, const double *p, int sp,
                   const double *Winv, double *work) {
  bc_f_fn f = (bc_f_fn)fn;
  size_t nn = (size_t)n * nx;
  double *fv = work, *k1 = work + nn, *xs = work + 2 * nn, *k2 = work + 3 * nn;
  double t = t0;
  for (int s = 0; s < m; ++s) {
    f(n, &t, 0, x, u, 0, z, d, sd, p, sp, 0.0, fv);
    bc_rows_product(n, nx, Winv, fv, k1);
    for (size_t i = 0; i < nn; ++i) xs[i] = x[i] + h * k1[i];
    f(n, &t, 0, xs, u, 0, z, d, sd, p, sp, 0.0, fv);
    for (size_t i = 0; i < nn; ++i) fv[i] -= 2.0 * k1[i];
    bc_rows_product(n, nx, Winv, fv, k2);
    for (size_t i = 0; i < nn; ++i) x[i] += 1.5 * h * k1[i] + 0.5 * h * k2[i];
    t += h;
  }
}
"""


def steps_driver():
    """The compiled ``bc_ros2_steps`` (ctypes function), or None without a C compiler."""
    from .c_build import driver_function
    vp, i, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    return driver_function(STEPS_SOURCE, "bc_ros2_steps", [vp, i, i, dbl, dbl, i, vp, vp, vp, vp, i, vp, i, vp, vp],
                           None)


def c_derivative(model):
    """The address of `model`'s generated ``bc_f`` when the C sub-step loop can run it: the C
    backend, no algebraic loops, and a driver compiled; else None."""
    if model.backend != "c" or model.algebraic_names or steps_driver() is None:
        return None
    main = getattr(getattr(model, "_k", None), "_main", None)
    fn = getattr(main, "f", None)
    return None if fn is None else ctypes.cast(fn, ctypes.c_void_p).value
