/* bondcosim FMU: event indicators and directional derivatives (Model Exchange,
   and directional derivatives for Co-Simulation too).  Included by
   bc_fmu_core.h after the checks it uses.

   Event indicators (BC_NEI of them, indicator_row in model_kernels.c): one per
   switching surface of the model's laws -- the argument g of sign(g), Abs(g),
   a - b of Max(a, b) / Min(a, b), lhs - rhs of each Piecewise inequality --
   so each changes sign exactly where a law switches branch and an importer's
   integrator can stop there instead of stepping across the kink or jump.
   The laws are not frozen between events: an integrator that overshoots a
   surface sees the new branch (the indicators only locate the switch).

   Directional derivatives: the Jacobian J = d(f, h)/d(x, u) at the current
   point, from the symbolic partials over w = (x, u, z) (partials_F_row,
   partials_r_row) with the algebraic unknowns z eliminated by the implicit-
   function theorem (bondgraph/linearization.py):

     dz/dw = -r_z^-1 r_w,   J = F_w + F_z dz/dw,

   then  dv_unknown = sum_k J[unknown, known_k] seed_k. */
#ifndef BC_PARTIALS_H
#define BC_PARTIALS_H

#include <stdlib.h>

/* The event indicators at the current point (loops solved first).  BC_OK,
   BC_DISCARD (the point is outside the domain, as bc_me_evaluate) or BC_ERROR. */
static int bc_event_indicators(bc_snapshot *s, double *out, size_t n, char *msg) {
  if (n != BC_NEI) {
    snprintf(msg, BC_MSG, "asked for %zu event indicators, the model has %d", n, BC_NEI);
    return BC_ERROR;
  }
#if BC_NEI > 0
  int r = bc_me_evaluate(s, msg);
  if (r) return r;
  double *v = s->v;
  indicator_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, out);
#else
  (void)s; (void)out;
#endif
  return BC_OK;
}

#if BC_HAS_DD
enum { BC_NF = BC_NX + BC_NY, BC_NW = BC_NX + BC_NU, BC_NWZ = BC_NX + BC_NU + BC_NZ };

/* J (BC_NF x BC_NW, row-major) at the current point; 0, or 1 with msg set. */
static int bc_jacobian(bc_snapshot *s, double *J, char *msg) {
  double *v = s->v;
  double *F = (double *)malloc(sizeof(double) * (size_t)(BC_NF > 0 ? BC_NF : 1) * BC_NWZ);
  if (!F) { snprintf(msg, BC_MSG, "out of memory"); return 1; }
  partials_F_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, F);
  for (int i = 0; i < BC_NF; ++i)
    for (int j = 0; j < BC_NW; ++j) J[i * BC_NW + j] = F[i * BC_NWZ + j];
#if BC_NZ > 0
  /* column j: solve r_z y = r_w[:, j], then J[:, j] -= F_z y */
  double R[BC_NZ * BC_NWZ], A[BC_NZ * BC_NZ], y[BC_NZ];
  partials_r_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, R);
  for (int j = 0; j < BC_NW; ++j) {
    for (int a = 0; a < BC_NZ; ++a) {
      y[a] = R[a * BC_NWZ + j];
      for (int b = 0; b < BC_NZ; ++b) A[a * BC_NZ + b] = R[a * BC_NWZ + BC_NW + b];
    }
    if (bc_gauss(BC_NZ, A, y)) {
      free(F);
      snprintf(msg, BC_MSG, "directional derivative: dr/dz is singular at t = %.17g s", s->time);
      return 1;
    }
    for (int i = 0; i < BC_NF; ++i)
      for (int b = 0; b < BC_NZ; ++b) J[i * BC_NW + j] -= F[i * BC_NWZ + BC_NW + b] * y[b];
  }
#endif
  free(F);
  return 0;
}
#endif

/* Row of J for an unknown (der(x_i), an output, or a state that is an output:
   -1 - i for state i, whose derivative by state i is 1); column of J for a known
   (a state or an input).  -1000000 (unknown) / -1 (known) when not one. */
static int bc_unknown_row(unsigned vr) {
  if (vr >= BC_VR_DX && vr < BC_VR_DX + BC_NX) return (int)(vr - BC_VR_DX);
  if (vr >= BC_VR_Y && vr < BC_VR_Y + BC_NY) return BC_NX + (int)(vr - BC_VR_Y);
  if (vr < BC_NX) return -1 - (int)vr;
  return -1000000;
}

static int bc_known_column(unsigned vr) {
  if (vr < BC_NX) return (int)vr;
  if (vr >= BC_VR_U && vr < BC_VR_U + BC_NU) return BC_NX + (int)(vr - BC_VR_U);
  return -1;
}

/* sensitivity[a] = sum_k d unknown[a] / d known[k] * seed[k].  BC_OK, BC_DISCARD (the
   point is outside the domain), BC_ERROR (a variable that is not an unknown / a known
   of the Jacobian, or none is provided). */
static int bc_directional(bc_snapshot *s, const unsigned *unknown, size_t nu, const unsigned *known,
                          size_t nk, const double *seed, double *sensitivity, char *msg) {
#if BC_HAS_DD
  for (size_t a = 0; a < nu; ++a)
    if (bc_unknown_row(unknown[a]) == -1000000) {
      snprintf(msg, BC_MSG, "directional derivative of %s: only derivatives and outputs are "
               "unknowns", unknown[a] < BC_NV ? bc_names[unknown[a]] : "an unknown value reference");
      return BC_ERROR;
    }
  for (size_t k = 0; k < nk; ++k)
    if (bc_known_column(known[k]) < 0) {
      snprintf(msg, BC_MSG, "directional derivative with respect to %s: only states and inputs "
               "are knowns", known[k] < BC_NV ? bc_names[known[k]] : "an unknown value reference");
      return BC_ERROR;
    }
  int r = bc_me_evaluate(s, msg);
  if (r) return r;
  double *J = (double *)malloc(sizeof(double) * (size_t)(BC_NF > 0 ? BC_NF : 1) * (BC_NW > 0 ? BC_NW : 1));
  if (!J) { snprintf(msg, BC_MSG, "out of memory"); return BC_ERROR; }
  if (bc_jacobian(s, J, msg)) { free(J); return BC_DISCARD; }
  for (size_t a = 0; a < nu; ++a) {
    int row = bc_unknown_row(unknown[a]);
    double sum = 0.0;
    for (size_t k = 0; k < nk; ++k) {
      int col = bc_known_column(known[k]);
      sum += (row >= 0 ? J[row * BC_NW + col] : (col == -1 - row ? 1.0 : 0.0)) * seed[k];
    }
    sensitivity[a] = sum;
  }
  free(J);
  return BC_OK;
#else
  (void)s; (void)unknown; (void)nu; (void)known; (void)nk; (void)seed; (void)sensitivity;
  snprintf(msg, BC_MSG, "this FMU provides no directional derivatives (its laws have no "
           "symbolic derivative)");
  return BC_ERROR;
#endif
}

#endif
