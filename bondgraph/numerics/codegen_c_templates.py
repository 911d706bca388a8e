"""Fixed C of every generated ``"main"`` library: the Newton solver and the RK4 driver.

:func:`bondgraph.numerics.codegen_c.generate_source` appends :func:`newton_source`
(``bc_solve``) and :func:`rk4_source` (``bc_rk4``) to the row functions it
generates from the model (``residuals_row``, ``jac_rz_row``, ``f_row``,
``held_update_row``); only sizes and the constants below are filled in.  Their
C signatures are part of the contract documented in :mod:`bondgraph.numerics.codegen_c`
(which re-exports the ``NEWTON_*`` constants), and the numpy backend
(:mod:`bondgraph.numerics.evaluate_numpy`) runs the same iterations with the same
tolerances.

Newton's method for :math:`0 = r(z)` on one row, warm-started in place:

.. math::

    J \\Delta z = -r, \\quad J = \\partial r / \\partial z,

a full step unless it increases :math:`|r|^2`, then halved at most 10 times;
converged when :math:`|\\Delta z_k| \\le` ``NEWTON_RTOL`` :math:`|z_k| +`
``NEWTON_ATOL`` for every k, or at the residual's rounding floor: where every
:math:`|\\Delta z_k| \\le` ``NEWTON_FLOOR_RTOL`` :math:`|z_k| +` ``NEWTON_ATOL`` and no
trial step lowers :math:`|r|^2` (z kept), or after ``NEWTON_FLOOR_RUN`` such steps in a
row (Newton near a simple root meets the first test in the step after so small a one).  A
loop whose residual subtracts absolute levels, such as the temperatures of two blocks at
296 K across a friction law of slope 3400, evaluates it to about 1e-10 at the root, and the
steps then stay near 2e-14, above the absolute tolerance, however long Newton iterates.  The
linear solve is Gaussian elimination with partial pivoting.
"""
from __future__ import annotations

__all__ = [
    "newton_source", "rk4_source", "BATCH_HEAD",
    "NEWTON_OK", "NEWTON_STATUS", "NEWTON_MAX_ITER", "NEWTON_RTOL", "NEWTON_ATOL", "NEWTON_FLOOR_RTOL",
    "NEWTON_FLOOR_RUN",
]

#: Relative / absolute step tolerance of the Newton iteration:
#: converged when :math:`|\\Delta z_i| \\le 10^{-12} |z_i| + 10^{-14}` for all i.
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14
#: Relative step below which an iterate that no trial step improves, or the last of
#: :data:`NEWTON_FLOOR_RUN` such steps in a row, is at the residual's rounding floor: converged
#: (see the module docstring).
NEWTON_FLOOR_RTOL = 1e-6
NEWTON_FLOOR_RUN = 3
#: Most Newton iterations per row.
NEWTON_MAX_ITER = 50
#: Status codes of :func:`bc_solve` rows.
NEWTON_OK = 0
NEWTON_STATUS = {
    1: f"no convergence in {NEWTON_MAX_ITER} Newton iterations",
    2: "singular Jacobian dr/dz",
    3: "residual is not finite (NaN or inf)",
}
#: Parameters of every batch function ``bc_<name>`` (see :mod:`bondgraph.numerics.codegen_c`);
#: ``{zc}`` is ``"const "`` for the kernels and ``""`` for ``bc_solve`` (z in/out).
BATCH_HEAD = ("int n, const double *t, int st, const double *x, const double *u, int su, "
              "{zc}double *z, const double *d, int sd, const double *p, int sp, double step")


# -- Newton ------------------------------------------------------------------

_NEWTON_TEMPLATE = r"""
/* Solve A y = b in place (A: m x m row-major, overwritten) by Gaussian
   elimination with partial pivoting.  Returns 1 when A is singular. */
static int bc_gauss(int m, double *A, double *b) {
  for (int k = 0; k < m; ++k) {
    int piv = k;
    double amax = fabs(A[k * m + k]);
    for (int i = k + 1; i < m; ++i) {
      double a = fabs(A[i * m + k]);
      if (a > amax) { amax = a; piv = i; }
    }
    if (!(amax > 1e-300) || !isfinite(amax)) return 1;
    if (piv != k) {
      for (int j = 0; j < m; ++j) { double s = A[k * m + j]; A[k * m + j] = A[piv * m + j]; A[piv * m + j] = s; }
      double s = b[k]; b[k] = b[piv]; b[piv] = s;
    }
    for (int i = k + 1; i < m; ++i) {
      double l = A[i * m + k] / A[k * m + k];
      if (l == 0.0) continue;
      for (int j = k; j < m; ++j) A[i * m + j] -= l * A[k * m + j];
      b[i] -= l * b[k];
    }
  }
  for (int k = m - 1; k >= 0; --k) {
    double s = b[k];
    for (int j = k + 1; j < m; ++j) s -= A[k * m + j] * b[j];
    b[k] = s / A[k * m + k];
  }
  return 0;
}

static double bc_norm2(int m, const double *r) {
  double s = 0.0;
  for (int k = 0; k < m; ++k) s += r[k] * r[k];
  return s;
}

static int bc_newton_iterate(double t, const double *x, const double *u, double *z,
                             const double *d, const double *p, double step, double *r,
                             double nr, double *J, double *dz, double *zt, double *rt);

/* Newton iteration for 0 = r(z) on one row, z warm-started in place.
   Step: J dz = -r with J = dr/dz; full step unless it increases |r|^2, then
   halve it (at most 10 times).  Converged when every |dz_k| <= RTOL |z_k| + ATOL. */
static int bc_newton_row(double t, const double *x, const double *u, double *z,
                         const double *d, const double *p, double step) {
  WORKSPACE_
  residuals_row(t, x, u, z, d, p, step, r);
  double nr = bc_norm2(NZ_, r);
  int status = 1;
  if (!isfinite(nr)) status = 3;
  else if (nr == 0.0) status = 0;
  else status = bc_newton_iterate(t, x, u, z, d, p, step, r, nr, J, dz, zt, rt);
  RELEASE_
  return status;
}

static int bc_newton_iterate(double t, const double *x, const double *u, double *z,
                             const double *d, const double *p, double step, double *r,
                             double nr, double *J, double *dz, double *zt, double *rt) {
  int tiny_run = 0;
  for (int it = 0; it < MAXIT_; ++it) {
    jac_rz_row(t, x, u, z, d, p, step, J);
    for (int k = 0; k < NZ_; ++k) dz[k] = -r[k];
    if (bc_gauss(NZ_, J, dz)) return 2;
    int small = 1, tiny = 1;
    for (int k = 0; k < NZ_; ++k) {
      if (!isfinite(dz[k])) return 2;
      if (fabs(dz[k]) > RTOL_ * fabs(z[k]) + ATOL_) small = 0;
      if (fabs(dz[k]) > FLOOR_RTOL_ * fabs(z[k]) + ATOL_) tiny = 0;
    }
    double lam = 1.0, nrt = 0.0;
    int accepted = 0;
    for (int ls = 0; ls <= 10; ++ls) {
      for (int k = 0; k < NZ_; ++k) zt[k] = z[k] + lam * dz[k];
      residuals_row(t, x, u, zt, d, p, step, rt);
      nrt = bc_norm2(NZ_, rt);
      if (isfinite(nrt) && (nrt <= nr || small)) { accepted = 1; break; }
      lam *= 0.5;
    }
    if (!accepted && tiny) return 0;   /* no step lowers |r|: its rounding floor, z kept */
    if (!isfinite(nrt)) return 3;
    for (int k = 0; k < NZ_; ++k) { z[k] = zt[k]; r[k] = rt[k]; }
    nr = nrt;
    if ((small && lam == 1.0) || nr == 0.0) return 0;
    tiny_run = tiny ? tiny_run + 1 : 0;
    if (tiny_run >= FLOOR_RUN_) return 0;   /* tiny steps that never become small: its floor */
  }
  return 1;
}
"""


def newton_source(dims: dict) -> list[str]:
    """C lines of ``bc_solve`` (and, with algebraic unknowns, the Newton solver it calls).

    Parameters
    ----------
    dims : dict str -> int
        ``NX``, ``NZ`` (and the other sizes) of the model.

    Returns
    -------
    list of str
    """
    nz, nx = dims["NZ"], dims["NX"]
    head = BATCH_HEAD.format(zc="")
    lines = [f"int bc_solve({head}, int *status) {{", "  int bad = 0;"]
    if nz:
        if nz <= 64:   # workspace on the stack (<= 34 kB)
            work = (f"double r[{nz}], J[{nz * nz}], dz[{nz}], zt[{nz}], rt[{nz}];", "")
        else:
            work = (f"double *r = (double *)malloc(sizeof(double) * {nz * nz + 4 * nz});\n"
                    "  if (!r) return 2;\n"
                    f"  double *J = r + {nz}, *dz = J + {nz * nz}, *zt = dz + {nz}, *rt = zt + {nz};",
                    "free(r);")
        body = (_NEWTON_TEMPLATE.replace("WORKSPACE_", work[0]).replace("RELEASE_", work[1])
                .replace("NZ_", str(nz)).replace("MAXIT_", str(NEWTON_MAX_ITER))
                .replace("FLOOR_RTOL_", repr(NEWTON_FLOOR_RTOL)).replace("FLOOR_RUN_", str(NEWTON_FLOOR_RUN))
                .replace("RTOL_", repr(NEWTON_RTOL)).replace("ATOL_", repr(NEWTON_ATOL)))
        lines = body.splitlines() + lines
        lines += [
            "  for (int i = 0; i < n; ++i) {",
            f"    status[i] = bc_newton_row(t[(size_t)i * st], x + (size_t)i * {nx}, "
            f"u + (size_t)i * su, z + (size_t)i * {nz}, d + (size_t)i * sd, "
            "p + (size_t)i * sp, step);",
            "    if (status[i]) ++bad;",
            "  }",
        ]
    else:
        lines.append("  for (int i = 0; i < n; ++i) status[i] = 0;")
    lines += ["  return bad;", "}"]
    return lines


# -- RK4 ---------------------------------------------------------------------

def rk4_source(dims: dict) -> list[str]:
    """C lines of ``bc_rk4``: m classic RK4 sub-steps of length h per row, u constant,
    held values updated at each sub-step start, z solved at every stage; and of
    ``bc_rk4_every``, which updates them only at every `every`-th sub-step start, over
    ``every h`` (finer steps nested in a discrete law's interval).

    Where the including code defines ``BC_STAGE_CHECK(t, x, u, z, d, p)`` (the FMU core
    does, over the model's guards), the states of stages 2-4 are checked with it: a
    nonzero result ends the row with that status (above the Newton codes), so a
    sub-step whose stages leave the physical domain is never accepted.  Without the
    macro the code is the same as before (``bondgraph.numerics.simulate``).

    Parameters
    ----------
    dims : dict str -> int
        ``NX``, ``NZ``, ``ND`` (and the other sizes) of the model.

    Returns
    -------
    list of str
    """
    nx, nz, nd = dims["NX"], dims["NZ"], dims["ND"]

    def solve(tt, xx, indent):
        if not nz:
            return []
        return [f"{indent}s = bc_newton_row({tt}, {xx}, ui, zi, di, pi, 0.0);",
                f"{indent}if (s) {{ for (int q = 0; q < {nz}; ++q) zi[q] = zinit[q];",
                f"{indent}  s = bc_newton_row({tt}, {xx}, ui, zi, di, pi, 0.0); }}",
                f"{indent}if (s) break;"]

    def stage(k, tt, xx):
        # A stage state outside the model's domain (a chamber volume below 0 between two
        # sub-step ends) makes the sub-step meaningless: with BC_STAGE_CHECK defined (the
        # FMU defines it over its guards) the row stops with status BC_STAGE_LEFT + guard.
        check = [] if xx == "xi" else [
            "#ifdef BC_STAGE_CHECK",
            f"      s = BC_STAGE_CHECK({tt}, {xx}, ui, zi, di, pi);",
            "      if (s) break;",
            "#endif"]
        return solve(tt, xx, "      ") + check + [f"      f_row({tt}, {xx}, ui, zi, di, pi, 0.0, {k});"]

    lines = [
        "int bc_rk4_every(int n, double t0, double h, int m, int every, double *x, const double *u, int su,",
        "                 double *z, const double *zinit, double *d, const double *p, int sp,",
        "                 int *status) {",
        f"  double *w = (double *)malloc(sizeof(double) * ({5 * nx + nd} + 1));",
        "  if (!w) return -1;",
        f"  double *k1 = w, *k2 = w + {nx}, *k3 = w + {2 * nx}, *k4 = w + {3 * nx};",
        f"  double *xt = w + {4 * nx}, *dn = w + {5 * nx};",
        "  (void)zinit; (void)dn; (void)every;",
        "  int bad = 0;",
        "  for (int i = 0; i < n; ++i) {",
        f"    double *xi = x + (size_t)i * {nx}, *zi = z + (size_t)i * {nz}, *di = d + (size_t)i * {nd};",
        "    const double *ui = u + (size_t)i * su, *pi = p + (size_t)i * sp;",
        "    int s = 0;",
        "    for (int j = 0; j < m; ++j) {",
        "      double t = t0 + j * h;",
    ]
    if nd:
        lines += ["      if (j % every == 0) {"]
        lines += solve("t", "xi", "      ")
        lines += ["      held_update_row(t, xi, ui, zi, di, pi, h * every, dn);",
                  f"      for (int q = 0; q < {nd}; ++q) di[q] = dn[q];",
                  "      }"]
    lines += stage("k1", "t", "xi")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + 0.5 * h * k1[q];"]
    lines += stage("k2", "t + 0.5 * h", "xt")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + 0.5 * h * k2[q];"]
    lines += stage("k3", "t + 0.5 * h", "xt")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + h * k3[q];"]
    lines += stage("k4", "t + h", "xt")
    lines += [
        f"      for (int q = 0; q < {nx}; ++q)",
        "        xi[q] += (h / 6.0) * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q]);",
        "    }",
        "    status[i] = s;",
        "    if (s) ++bad;",
        "  }",
        "  free(w);",
        "  return bad;",
        "}",
        "int bc_rk4(int n, double t0, double h, int m, double *x, const double *u, int su,",
        "           double *z, const double *zinit, double *d, const double *p, int sp,",
        "           int *status) {",
        "  return bc_rk4_every(n, t0, h, m, 1, x, u, su, z, zinit, d, p, sp, status);",
        "}",
    ]
    return lines
