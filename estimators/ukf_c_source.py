"""C source of the UKF step kernel: the model's generated C plus one fixed UKF template.

:func:`ukf_source` appends :data:`UKF_TEMPLATE` to the model's ``"main"``
library source (:func:`bondgraph.numerics.codegen_c.generate_source`: row kernels,
``bc_rk4``) and fills in the sizes and the workspace layout.  The result is one
translation unit, compiled and cached by :func:`bondgraph.numerics.c_build.compile_source`.

C contract
----------
All state lives in one ``double`` workspace ``ws`` laid out by :func:`layout`
(the same table gives the offsets ``UKF_O_<NAME>`` in C and the numpy views
in :mod:`estimators.ukf_c`)::

    int bc_ukf_predict(double *ws, int *info)   /* eqs. (13)-(18) of [1]_          */
    int bc_ukf_update(double *ws, int *info)    /* eqs. (19)-(24) of [1]_          */
    int bc_ukf_step(double *ws, int *info)      /* check u, y finite; both steps   */
    int bc_ukf_run(double *ws, int n, const double *U, const double *Z,
                   double *X, double *P, int *info)
        /* n steps: u = U[k] (n, NU), y = Z[k] (n, NY), bc_ukf_step,
           X[k] = x (n, NF), P[k] = P (n, NF, NF); info[0] = steps done */

Each returns 0 or a status of :data:`STATUS` (``info[1]`` = the offending
sigma point for model failures; after ``bc_ukf_step``, ``info[2]`` = 1 when
the prediction was made).  The kernel does the same arithmetic as the
numpy reference engine (:mod:`estimators.ukf_engine`: sigma points from the
lower Cholesky factor, ``sqrtc * L[:, i]``; sums over sigma points in order;
:math:`K` by two triangular solves with the Cholesky factor of :math:`S`), so
both agree to rounding.

References
----------
.. [1] T. Shin, T. Ibayashi, K. Kogiso, "Detailed dynamic model of antagonistic
   PAM system and its experimental validation", seed 000 (``docs/references.md``),
   Section III-A.
"""
from __future__ import annotations

__all__ = ["ukf_source", "layout", "STATUS", "UKF_TEMPLATE_VERSION"]

UKF_TEMPLATE_VERSION = "bondcosim-ukf-c 1"

#: Status codes of the kernel: code -> (matrix or argument name, message).
STATUS = {
    1: ("P", "the covariance P is not positive definite (Cholesky failed) when drawing the sigma points"),
    2: ("fx", "the model's RK4 failed (Newton's method on an algebraic loop) for sigma point {row}"),
    3: ("fx", "the model's RK4 gave non-finite states for sigma point {row}"),
    4: ("P_prior", "the prior covariance P⁻ is not positive definite (Cholesky failed) when "
                   "redrawing the sigma points"),
    5: ("S", "the innovation covariance S = P_yy is not positive definite (Cholesky failed)"),
    6: ("z", "the measurement is not finite (NaN or inf)"),
    7: ("hx", "the model's outputs are not finite at sigma point {row}"),
    8: ("fx", "out of memory in the model's RK4"),
    9: ("u", "the input is not finite (NaN or inf)"),
}


def layout(nf: int, nm: int, ny: int, nu: int, nd: int, npar: int, nym: int) -> list:
    """``[(name, offset, size), ...]`` of the workspace (doubles).

    Inputs: ``x``, ``P`` (filter state), ``Q``, ``R``, ``Wm``, ``Wc``, ``sqrtc``
    (:math:`\\sqrt c`), ``T``, ``Ti`` (state map and inverse), ``p``, ``d``,
    ``u``, ``y`` (measurement), ``t``, ``h`` (sub-step, s), ``m`` (sub-steps),
    ``dt``.  Outputs: ``x_prior``, ``P_prior``, ``yhat``, ``S``, ``K``,
    ``innov``.  Scratch: the rest.
    """
    ns = 2 * nf + 1
    sizes = [("x", nf), ("P", nf * nf), ("Q", nf * nf), ("R", ny * ny), ("Wm", ns), ("Wc", ns),
             ("sqrtc", 1), ("T", nm * nf), ("Ti", nf * nm), ("p", npar), ("d", nd), ("u", nu),
             ("y", ny), ("t", 1), ("h", 1), ("m", 1), ("dt", 1),
             ("x_prior", nf), ("P_prior", nf * nf), ("yhat", ny), ("S", ny * ny), ("K", nf * ny),
             ("innov", ny),
             ("L", nf * nf), ("sig", ns * nf), ("Xm", ns * nm), ("D", ns * nd), ("Xp", ns * nf),
             ("Y", ns * ny), ("hout", nym), ("Ls", ny * ny), ("Pxy", nf * ny), ("KS", nf * ny),
             ("zdummy", 1)]
    out, off = [], 0
    for name, size in sizes:
        out.append((name, off, size))
        off += size
    return out


UKF_TEMPLATE = r"""
/* ---- UKF step kernel: __VERSION__ ---- */
#define NF __NF__
#define NM __NM__
#define NS (2 * NF + 1)
#define NYM_ __NY__
#define NU_ __NU__
#define ND_ __ND__
#define REDRAW __REDRAW__
#define HAS_MAP __MAP__
__OFFSETS__
static const int ukf_out[NYM_] = {__OUTIDX__};

/* Lower Cholesky factor L of the n x n matrix A (L L^T = A; upper part set to 0).
   Returns 1 when a pivot is not positive and finite (A not positive definite). */
static int ukf_chol(int n, const double *A, double *L) {
  for (int j = 0; j < n; ++j) {
    double s = A[j * n + j];
    for (int k = 0; k < j; ++k) s -= L[j * n + k] * L[j * n + k];
    if (!(s > 0.0) || !isfinite(s)) return 1;
    const double ljj = sqrt(s);
    L[j * n + j] = ljj;
    for (int i = j + 1; i < n; ++i) {
      double v = A[i * n + j];
      for (int k = 0; k < j; ++k) v -= L[i * n + k] * L[j * n + k];
      L[i * n + j] = v / ljj;
    }
    for (int i = 0; i < j; ++i) L[i * n + j] = 0.0;
  }
  return 0;
}

/* Sigma points, eqs. (13)-(15): x, x + sqrtc L[:, i], x - sqrtc L[:, i]. */
static void ukf_spread(const double *x, const double *L, double sc, double *sig) {
  for (int j = 0; j < NF; ++j) sig[j] = x[j];
  for (int i = 0; i < NF; ++i)
    for (int j = 0; j < NF; ++j) {
      const double a = sc * L[j * NF + i];
      sig[(1 + i) * NF + j] = x[j] + a;
      sig[(1 + NF + i) * NF + j] = x[j] - a;
    }
}

/* Filter -> model coordinates of NS points: Xm = T X (T: NM x NF). */
static void ukf_to_model(const double *ws, const double *X, double *Xm) {
#if HAS_MAP
  const double *T = ws + UKF_O_T;
  for (int s = 0; s < NS; ++s)
    for (int r = 0; r < NM; ++r) {
      double acc = 0.0;
      for (int c = 0; c < NF; ++c) acc += T[r * NF + c] * X[s * NF + c];
      Xm[s * NM + r] = acc;
    }
#else
  (void)ws;
  memcpy(Xm, X, sizeof(double) * NS * NF);
#endif
}

/* Model -> filter coordinates: X = Ti Xm (Ti: NF x NM). */
static void ukf_to_filter(const double *ws, const double *Xm, double *X) {
#if HAS_MAP
  const double *Ti = ws + UKF_O_TI;
  for (int s = 0; s < NS; ++s)
    for (int r = 0; r < NF; ++r) {
      double acc = 0.0;
      for (int c = 0; c < NM; ++c) acc += Ti[r * NM + c] * Xm[s * NM + c];
      X[s * NF + r] = acc;
    }
#else
  (void)ws;
  memcpy(X, Xm, sizeof(double) * NS * NF);
#endif
}

/* Weighted mean of NS rows of width w: out = sum_s W_s X_s. */
static void ukf_mean(int w, const double *W, const double *X, double *out) {
  for (int j = 0; j < w; ++j) {
    double acc = 0.0;
    for (int s = 0; s < NS; ++s) acc += W[s] * X[s * w + j];
    out[j] = acc;
  }
}

int bc_ukf_predict(double *ws, int *info) {
  double *x = ws + UKF_O_X, *P = ws + UKF_O_P, *L = ws + UKF_O_L, *sig = ws + UKF_O_SIG;
  double *Xm = ws + UKF_O_XM, *D = ws + UKF_O_D, *Xp = ws + UKF_O_XP, *d = ws + UKF_O_D_;
  const double *Wm = ws + UKF_O_WM, *Wc = ws + UKF_O_WC, *Q = ws + UKF_O_Q;
  int st[NS];
  (void)D; (void)d;
  /* sigma points of the posterior, eqs. (13)-(15) */
  if (ukf_chol(NF, P, L)) return 1;
  ukf_spread(x, L, ws[UKF_O_SQRTC], sig);
  ukf_to_model(ws, sig, Xm);
  /* eq. (16): every point starts from the filter's held values; one batched RK4 */
  for (int s = 0; s < NS; ++s)
    for (int q = 0; q < ND_; ++q) D[s * ND_ + q] = d[q];
  const int bad = bc_rk4(NS, ws[UKF_O_T_], ws[UKF_O_H], (int)ws[UKF_O_M], Xm, ws + UKF_O_U, 0,
                         ws + UKF_O_ZDUMMY, ws + UKF_O_ZDUMMY, D, ws + UKF_O_P_, 0, st);
  if (bad < 0) return 8;
  if (bad) {
    for (int s = 0; s < NS; ++s) if (st[s]) { info[1] = s; break; }
    return 2;
  }
  ukf_to_filter(ws, Xm, Xp);
  for (int s = 0; s < NS; ++s)
    for (int j = 0; j < NF; ++j)
      if (!isfinite(Xp[s * NF + j])) { info[1] = s; return 3; }
  /* held values advance with the central point (row 0 = the posterior mean) */
  for (int q = 0; q < ND_; ++q) d[q] = D[q];
  /* eq. (17): prior mean; eq. (18): prior covariance (upper triangle, mirrored) */
  double *xp = ws + UKF_O_X_PRIOR, *Pp = ws + UKF_O_P_PRIOR;
  ukf_mean(NF, Wm, Xp, xp);
  for (int i = 0; i < NF; ++i)
    for (int j = i; j < NF; ++j) {
      double acc = 0.0;
      for (int s = 0; s < NS; ++s)
        acc += Wc[s] * (Xp[s * NF + i] - xp[i]) * (Xp[s * NF + j] - xp[j]);
      Pp[i * NF + j] = Pp[j * NF + i] = acc + Q[i * NF + j];
    }
  memcpy(x, xp, sizeof(double) * NF);
  memcpy(P, Pp, sizeof(double) * NF * NF);
  ws[UKF_O_T_] += ws[UKF_O_DT];
  return 0;
}

int bc_ukf_update(double *ws, int *info) {
  const double *xp = ws + UKF_O_X_PRIOR, *Pp = ws + UKF_O_P_PRIOR, *y = ws + UKF_O_Y;
  const double *Wm = ws + UKF_O_WM, *Wc = ws + UKF_O_WC, *R = ws + UKF_O_R;
  double *Xm = ws + UKF_O_XM, *Y = ws + UKF_O_YY, *yh = ws + UKF_O_YHAT, *S = ws + UKF_O_S;
  double *Ls = ws + UKF_O_LS, *Pxy = ws + UKF_O_PXY, *K = ws + UKF_O_K, *KS = ws + UKF_O_KS;
  double *inn = ws + UKF_O_INNOV, *x = ws + UKF_O_X, *P = ws + UKF_O_P, *hout = ws + UKF_O_HOUT;
  for (int k = 0; k < NYM_; ++k) if (!isfinite(y[k])) return 6;
#if REDRAW
  /* sigma points recomputed from the prior x^-, P^- (paper, before eq. (19)) */
  double *X = ws + UKF_O_SIG;
  if (ukf_chol(NF, Pp, ws + UKF_O_L)) return 4;
  ukf_spread(xp, ws + UKF_O_L, ws[UKF_O_SQRTC], X);
#else
  /* the propagated points themselves (filterpy <= 1.4) */
  const double *X = ws + UKF_O_XP;
#endif
  /* eq. (19): measured outputs of every point */
  ukf_to_model(ws, X, Xm);
  for (int s = 0; s < NS; ++s) {
    h_row(ws[UKF_O_T_], Xm + s * NM, ws + UKF_O_U, ws + UKF_O_ZDUMMY, ws + UKF_O_D_,
          ws + UKF_O_P_, 0.0, hout);
    for (int k = 0; k < NYM_; ++k) {
      Y[s * NYM_ + k] = hout[ukf_out[k]];
      if (!isfinite(Y[s * NYM_ + k])) { info[1] = s; return 7; }
    }
  }
  /* eqs. (20)-(22): predicted measurement, S = P_yy + R, P_xy */
  ukf_mean(NYM_, Wm, Y, yh);
  for (int i = 0; i < NYM_; ++i)
    for (int j = i; j < NYM_; ++j) {
      double acc = 0.0;
      for (int s = 0; s < NS; ++s)
        acc += Wc[s] * (Y[s * NYM_ + i] - yh[i]) * (Y[s * NYM_ + j] - yh[j]);
      S[i * NYM_ + j] = S[j * NYM_ + i] = acc + R[i * NYM_ + j];
    }
  for (int i = 0; i < NF; ++i)
    for (int j = 0; j < NYM_; ++j) {
      double acc = 0.0;
      for (int s = 0; s < NS; ++s)
        acc += Wc[s] * (X[s * NF + i] - xp[i]) * (Y[s * NYM_ + j] - yh[j]);
      Pxy[i * NYM_ + j] = acc;
    }
  /* K = P_xy S^-1: S = Ls Ls^T, solve Ls Ls^T K[i, :]^T = P_xy[i, :]^T row by row */
  if (ukf_chol(NYM_, S, Ls)) return 5;
  for (int i = 0; i < NF; ++i) {
    double *k = K + i * NYM_;
    for (int a = 0; a < NYM_; ++a) {
      double v = Pxy[i * NYM_ + a];
      for (int b = 0; b < a; ++b) v -= Ls[a * NYM_ + b] * k[b];
      k[a] = v / Ls[a * NYM_ + a];
    }
    for (int a = NYM_ - 1; a >= 0; --a) {
      double v = k[a];
      for (int b = a + 1; b < NYM_; ++b) v -= Ls[b * NYM_ + a] * k[b];
      k[a] = v / Ls[a * NYM_ + a];
    }
  }
  /* eq. (23): x = x^- + K (y - y^-); eq. (24): P = P^- - K S K^T (upper, mirrored) */
  for (int k = 0; k < NYM_; ++k) inn[k] = y[k] - yh[k];
  for (int i = 0; i < NF; ++i) {
    double acc = 0.0;
    for (int k = 0; k < NYM_; ++k) acc += K[i * NYM_ + k] * inn[k];
    x[i] = xp[i] + acc;
  }
  for (int i = 0; i < NF; ++i)
    for (int k = 0; k < NYM_; ++k) {
      double acc = 0.0;
      for (int a = 0; a < NYM_; ++a) acc += K[i * NYM_ + a] * S[a * NYM_ + k];
      KS[i * NYM_ + k] = acc;
    }
  for (int i = 0; i < NF; ++i)
    for (int j = i; j < NF; ++j) {
      double acc = 0.0;
      for (int k = 0; k < NYM_; ++k) acc += KS[i * NYM_ + k] * K[j * NYM_ + k];
      P[i * NF + j] = P[j * NF + i] = Pp[i * NF + j] - acc;
    }
  return 0;
}

/* One step: u and y already in the workspace; info[2] = 1 once the prediction is done. */
int bc_ukf_step(double *ws, int *info) {
  info[2] = 0;
  for (int j = 0; j < NU_; ++j) if (!isfinite(ws[UKF_O_U + j])) return 9;
  for (int j = 0; j < NYM_; ++j) if (!isfinite(ws[UKF_O_Y + j])) return 6;
  int s = bc_ukf_predict(ws, info);
  if (s) return s;
  info[2] = 1;
  return bc_ukf_update(ws, info);
}

int bc_ukf_run(double *ws, int n, const double *U, const double *Z, double *X, double *Pout,
               int *info) {
  for (int k = 0; k < n; ++k) {
    info[0] = k;
    memcpy(ws + UKF_O_U, U + (size_t)k * NU_, sizeof(double) * NU_);
    memcpy(ws + UKF_O_Y, Z + (size_t)k * NYM_, sizeof(double) * NYM_);
    const int s = bc_ukf_step(ws, info);
    if (s) return s;
    memcpy(X + (size_t)k * NF, ws + UKF_O_X, sizeof(double) * NF);
    memcpy(Pout + (size_t)k * NF * NF, ws + UKF_O_P, sizeof(double) * NF * NF);
  }
  info[0] = n;
  return 0;
}
"""

# C macro names of the layout entries that would clash with other names
_MACRO = {"t": "T_", "d": "D_", "p": "P_", "Y": "YY", "T": "T", "D": "D", "P": "P"}


def _macro(name: str) -> str:
    return "UKF_O_" + _MACRO.get(name, name.upper())


def ukf_source(model_source: str, *, nf: int, nm: int, nu: int, nd: int, npar: int, nym_model: int,
               output_index, redraw: bool, has_map: bool) -> str:
    """One C translation unit: the model's ``"main"`` source and the UKF kernel.

    Parameters
    ----------
    model_source : str
        :func:`bondgraph.numerics.codegen_c.generate_source` of the model (``part="main"``),
        which defines ``h_row`` and ``bc_rk4``; the model must have no algebraic unknowns.
    nf, nm : int
        Filter and model state dimensions (equal; kept apart for clarity).
    nu, nd, npar, nym_model : int
        Model inputs, held variables, parameters and outputs.
    output_index : sequence of int
        Model outputs measured, in measurement order.
    redraw : bool
        Redraw the sigma points from the prior before the measurement transform.
    has_map : bool
        Apply the state map ``T`` / ``Ti`` of the workspace.

    Returns
    -------
    str
    """
    ny = len(output_index)
    offsets = "\n".join(f"#define {_macro(name)} {off}"
                        for name, off, _ in layout(nf, nm, ny, nu, nd, npar, nym_model))
    text = (UKF_TEMPLATE.replace("__VERSION__", UKF_TEMPLATE_VERSION)
            .replace("__NF__", str(nf)).replace("__NM__", str(nm)).replace("__NY__", str(ny))
            .replace("__NU__", str(nu)).replace("__ND__", str(nd))
            .replace("__REDRAW__", "1" if redraw else "0").replace("__MAP__", "1" if has_map else "0")
            .replace("__OFFSETS__", offsets)
            .replace("__OUTIDX__", ", ".join(str(int(i)) for i in output_index)))
    return model_source + text
