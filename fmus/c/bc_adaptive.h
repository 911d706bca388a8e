/* bondcosim FMU: the variable-step Co-Simulation solver (solver = 1).

   Dormand-Prince 5(4) [1] with local extrapolation (the 5th-order solution is
   kept), FSAL, and the standard error control of [2], sec. II.4:

     err = sqrt(mean_i (e_i / (atol + rtol max(|x_i|, |x_i'|)))^2),  atol = rtol * nominal_i
     h_new = h * min(5, max(0.2, 0.9 err^(-1/5)))

   A step is accepted when err <= 1; the accepted step size carries over to the
   next doStep (bc_snapshot.h_adapt).  Inputs are held over the communication
   step, algebraic loops are solved at every stage, the physical domain
   (bc_check_domain) is checked after every accepted step, and attempts count
   against max_substeps exactly as RK4 sub-steps do.  Offered only by models
   without held variables (those define their physics per fixed sub-step).

   [1] J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta
       formulae", J. Comput. Appl. Math. 6 (1980) 19-26, Table 2.
   [2] E. Hairer, S. P. Norsett, G. Wanner, Solving Ordinary Differential
       Equations I, 2nd ed., Springer 1993. */
#ifndef BC_ADAPTIVE_H
#define BC_ADAPTIVE_H

/* ", guards there: V_1 = 5e-05, ..." (every guard's value at t), or "" without guards. */
static void bc_guard_summary(bc_snapshot *s, double t, char *out, size_t size) {
  out[0] = '\0';
#if BC_NG > 0
  double g[BC_NGA], *v = s->v;
  guard_row(t, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, g);
  size_t k = (size_t)snprintf(out, size, "; guards there:");
  for (int i = 0; i < BC_NG && k < size; ++i)
    k += (size_t)snprintf(out + k, size - k, "%s %s = %.4g%s%s", i ? "," : "", bc_guard_names[i], g[i],
                          bc_guard_units[i][0] ? " " : "", bc_guard_units[i]);
#else
  (void)s; (void)t; (void)size;
#endif
}

/* dx = f(t, x) with the loops solved (warm start from s->z); 0 on success. */
static int bc_rhs(bc_snapshot *s, double t, const double *x, double *dx) {
  double *v = s->v;
#if BC_NZ > 0
  int status = bc_newton_row(t, x, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0);
  if (status) {
    memcpy(s->z, bc_zinit, sizeof(s->z));
    status = bc_newton_row(t, x, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0);
  }
  if (status) return 1;
#endif
  f_row(t, x, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, dx);
  for (int i = 0; i < BC_NX; ++i)
    if (!isfinite(dx[i])) return 1;
  return 0;
}

/* Advance s from t to t + H (s->time == t on entry); BC_OK, or BC_DISCARD with
   msg set (the caller restores the state). */
static int bc_dopri(bc_snapshot *s, double t, double H, char *msg) {
  /* Dormand-Prince coefficients [1] */
  static const double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  static const double a21 = 1.0 / 5;
  static const double a31 = 3.0 / 40, a32 = 9.0 / 40;
  static const double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  static const double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                      a54 = -212.0 / 729;
  static const double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                      a64 = 49.0 / 176, a65 = -5103.0 / 18656;
  static const double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                      b6 = 11.0 / 84;
  /* e = b (5th order) - b* (4th order) */
  static const double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                      e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;
  enum { N = BC_NXA };
  double k1[N], k2[N], k3[N], k4[N], k5[N], k6[N], k7[N], xt[N], xn[N];
  double *x = s->v + BC_VR_X;
  double rtol = s->v[BC_VR_TOL], tend = t + H, tc = t;
  double h = s->h_adapt > 0.0 ? s->h_adapt : fmin(H, s->v[BC_VR_STEP]);
  double attempts = 0.0, maxsub = s->v[BC_VR_MAXSUB];
  if (bc_rhs(s, tc, x, k1)) goto rhs_failed;
  while (tc < tend) {
    int last = tend - tc <= h * (1 + 1e-12);   /* the step reaches the end: clip it */
    double hs = last ? tend - tc : h;
    if (hs < 1e-12 * fmax(fabs(tc), H)) {   /* a singularity: the step shrinks without end */
      char guards[BC_MSG / 2];
      bc_guard_summary(s, tc, guards, sizeof(guards));
      snprintf(msg, BC_MSG, "variable-step solver: step size %g s underflows at t = %.17g s, "
               "near a singularity of the model%s", hs, tc, guards);
      return BC_DISCARD;
    }
    if (++attempts > maxsub) {
      snprintf(msg, BC_MSG, "variable-step doStep of H = %g s from t = %.17g s needs more than "
               "max_substeps = %.4g attempts (at t = %.17g s, h = %g s); take shorter "
               "communication steps or loosen the tolerance", H, t, maxsub, tc, hs);
      return BC_DISCARD;
    }
    for (int i = 0; i < BC_NX; ++i) xt[i] = x[i] + hs * a21 * k1[i];
    if (bc_rhs(s, tc + c2 * hs, xt, k2)) goto reject;
    for (int i = 0; i < BC_NX; ++i) xt[i] = x[i] + hs * (a31 * k1[i] + a32 * k2[i]);
    if (bc_rhs(s, tc + c3 * hs, xt, k3)) goto reject;
    for (int i = 0; i < BC_NX; ++i) xt[i] = x[i] + hs * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
    if (bc_rhs(s, tc + c4 * hs, xt, k4)) goto reject;
    for (int i = 0; i < BC_NX; ++i)
      xt[i] = x[i] + hs * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
    if (bc_rhs(s, tc + c5 * hs, xt, k5)) goto reject;
    for (int i = 0; i < BC_NX; ++i)
      xt[i] = x[i] + hs * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
    if (bc_rhs(s, tc + hs, xt, k6)) goto reject;
    for (int i = 0; i < BC_NX; ++i)
      xn[i] = x[i] + hs * (b1 * k1[i] + b3 * k3[i] + b4 * k4[i] + b5 * k5[i] + b6 * k6[i]);
    if (bc_rhs(s, tc + hs, xn, k7)) goto reject;
    {
      double err = 0.0;
      for (int i = 0; i < BC_NX; ++i) {
        double ei = hs * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
        double sc = rtol * bc_nominal[i] + rtol * fmax(fabs(x[i]), fabs(xn[i]));
        err += (ei / sc) * (ei / sc);
      }
      err = BC_NX ? sqrt(err / BC_NX) : 0.0;
      if (!isfinite(err)) goto reject;
      double grow = err > 0.0 ? 0.9 * pow(err, -0.2) : 5.0;
      grow = fmin(5.0, fmax(0.2, grow));
      if (err <= 1.0) {   /* accept: the 5th-order solution, FSAL */
        tc = last ? tend : tc + hs;
        memcpy(x, xn, sizeof(double) * BC_NX);
        memcpy(k1, k7, sizeof(double) * BC_NX);
        if (bc_check_domain(s, tc, msg)) return BC_DISCARD;
        if (!last || grow < 1.0) h = hs * grow;   /* a clipped step that went well keeps h */
      } else {
        h = hs * grow;
      }
      continue;
    }
  reject:   /* a stage left the model's domain of definition: halve and retry */
    h = 0.5 * hs;
  }
  s->h_adapt = h;
  return BC_OK;
rhs_failed:
  snprintf(msg, BC_MSG, "variable-step solver: the right-hand side is not finite or an "
           "algebraic loop fails at t = %.17g s", tc);
  return BC_DISCARD;
}

#endif
