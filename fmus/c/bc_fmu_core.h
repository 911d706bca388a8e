/* bondcosim FMU core: the model's numbers and what FMI calls do to them,
   independent of the FMI version.  Included by fmi2_wrapper.c and
   fmi3_wrapper.c after the generated "model.h" (sizes, value-reference
   layout, start values) and "model_kernels.c" (f_row, h_row, bc_rk4, ...;
   see bondgraph/codegen_c.py for their contract).

   Every variable lives in one array v[] indexed by its value reference:

     [BC_VR_X,  +NX)  continuous states x          (initial exact)
     [BC_VR_DX, +NX)  their derivatives dx/dt      (calculated)
     [BC_VR_U,  +NU)  inputs u
     [BC_VR_P,  +NP)  parameters p                 (fixed)
     [BC_VR_D,  +ND)  held (discrete) variables d  (initial exact)
     [BC_VR_Y,  +NY)  outputs y                    (calculated)
     BC_VR_STEP       the internal solver step, s  (fixed)

   so the generated kernels read x, u, p, d straight out of v[].  The whole
   numeric state of an instance is one bc_snapshot, which makes FMU state
   get/set a memcpy. */
#ifndef BC_FMU_CORE_H
#define BC_FMU_CORE_H

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { BC_INSTANTIATED, BC_INIT, BC_RUNNING, BC_TERMINATED, BC_FAILED };

typedef struct {
  double v[BC_NV];
  double z[BC_NZA];   /* algebraic unknowns (warm start of the Newton solver) */
  double time;        /* s */
  int phase;
  int dirty;          /* derivatives and outputs are stale */
} bc_snapshot;

#define BC_MSG 512

static void bc_reset(bc_snapshot *s, double time) {
  memcpy(s->v, bc_start, sizeof(s->v));
  memcpy(s->z, bc_zinit, sizeof(s->z));
  s->time = time;
  s->phase = BC_INSTANTIATED;
  s->dirty = 1;
}

/* Solve the algebraic loops at the current point (from the last solution,
   then from the initial guess).  0 on success. */
static int bc_solve_loops(bc_snapshot *s, char *msg) {
#if BC_NZ > 0
  double *v = s->v;
  int status = bc_newton_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D,
                             v + BC_VR_P, 0.0);
  if (status) {
    memcpy(s->z, bc_zinit, sizeof(s->z));
    status = bc_newton_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D,
                           v + BC_VR_P, 0.0);
  }
  if (status) {
    snprintf(msg, BC_MSG, "algebraic loop not solved at t = %.17g s (%s)", s->time,
             bc_newton_messages[status < 4 ? status : 0]);
    return 1;
  }
#else
  (void)s; (void)msg;
#endif
  return 0;
}

/* Bring derivatives and outputs up to date with time, states, inputs. */
static int bc_refresh(bc_snapshot *s, char *msg) {
  if (!s->dirty) return 0;
  double *v = s->v;
  if (bc_solve_loops(s, msg)) return 1;
  f_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, v + BC_VR_DX);
  h_row(s->time, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, v + BC_VR_Y);
  s->dirty = 0;
  return 0;
}

static int bc_check_states(const bc_snapshot *s, char *msg) {
  for (int i = 0; i < BC_NX; ++i) {
    if (!isfinite(s->v[BC_VR_X + i])) {
      snprintf(msg, BC_MSG, "state %s is not finite (%g) at t = %.17g s",
               bc_names[BC_VR_X + i], s->v[BC_VR_X + i], s->time);
      return 1;
    }
  }
  return 0;
}

/* Co-simulation step: classic RK4 in m equal sub-steps no longer than the
   solver step, inputs held, held variables updated at each sub-step start
   (bc_rk4).  On failure the state is left unchanged. */
static int bc_do_step(bc_snapshot *s, double t, double H, char *msg) {
  if (!(H > 0.0) || !isfinite(H)) {
    snprintf(msg, BC_MSG, "communication step %g s is not positive", H);
    return 1;
  }
  double tol = 1e-9 * (fabs(s->time) > 1.0 ? fabs(s->time) : 1.0);
  if (fabs(t - s->time) > tol) {
    snprintf(msg, BC_MSG, "doStep from t = %.17g s, but the FMU is at t = %.17g s", t, s->time);
    return 1;
  }
  double hmax = s->v[BC_VR_STEP];
  int m = (int)ceil(H / hmax - 1e-9);
  if (m < 1) m = 1;
  double v_old[BC_NV];
  memcpy(v_old, s->v, sizeof(v_old));
  int status = 0;
  double *v = s->v;
  int bad = bc_rk4(1, t, H / m, m, v + BC_VR_X, v + BC_VR_U, 0, s->z, bc_zinit, v + BC_VR_D,
                   v + BC_VR_P, 0, &status);
  s->dirty = 1;
  if (bad) {
    memcpy(s->v, v_old, sizeof(v_old));
    snprintf(msg, BC_MSG, "step from t = %.17g s failed: %s", t,
             bad < 0 ? "out of memory" : bc_newton_messages[status > 0 && status < 4 ? status : 0]);
    return 1;
  }
  if (bc_check_states(s, msg)) { memcpy(s->v, v_old, sizeof(v_old)); return 1; }
  s->time = t + H;
  return 0;
}

static int bc_settable(const bc_snapshot *s, unsigned vr, char *msg) {
  int before_init = s->phase == BC_INSTANTIATED || s->phase == BC_INIT;
  if (vr >= BC_NV) {
    snprintf(msg, BC_MSG, "no variable has value reference %u", vr);
    return 0;
  }
  if (vr >= BC_VR_U && vr < BC_VR_U + BC_NU) return 1;   /* inputs: always */
  if ((vr >= BC_VR_DX && vr < BC_VR_DX + BC_NX) || (vr >= BC_VR_Y && vr < BC_VR_Y + BC_NY)) {
    snprintf(msg, BC_MSG, "%s is calculated by the FMU and cannot be set", bc_names[vr]);
    return 0;
  }
  if (!before_init) {   /* states, parameters, held values, the solver step */
    snprintf(msg, BC_MSG, "%s can only be set before initialisation ends", bc_names[vr]);
    return 0;
  }
  return 1;
}

static int bc_set_real(bc_snapshot *s, const unsigned *vr, size_t n, const double *value, char *msg) {
  for (size_t i = 0; i < n; ++i) {
    if (!bc_settable(s, vr[i], msg)) return 1;
    if (vr[i] == BC_VR_STEP && !(value[i] > 0.0 && isfinite(value[i]))) {
      snprintf(msg, BC_MSG, "%s must be positive, got %g", bc_names[vr[i]], value[i]);
      return 1;
    }
  }
  for (size_t i = 0; i < n; ++i) s->v[vr[i]] = value[i];
  if (n) s->dirty = 1;
  return 0;
}

static int bc_get_real(bc_snapshot *s, const unsigned *vr, size_t n, double *value, char *msg) {
  for (size_t i = 0; i < n; ++i) {
    if (vr[i] >= BC_NV) {
      snprintf(msg, BC_MSG, "no variable has value reference %u", vr[i]);
      return 1;
    }
  }
  if (s->phase != BC_INSTANTIATED && bc_refresh(s, msg)) return 1;
  for (size_t i = 0; i < n; ++i) value[i] = s->v[vr[i]];
  return 0;
}

/* Serialized FMU state: a header (magic, size, token hash) then the snapshot. */
typedef struct { char magic[8]; unsigned long long size, token; } bc_state_header;

static unsigned long long bc_token_hash(void) {
  unsigned long long h = 1469598103934665603ULL;   /* FNV-1a */
  for (const char *c = BC_TOKEN; *c; ++c) { h ^= (unsigned char)*c; h *= 1099511628211ULL; }
  return h;
}

static size_t bc_serialized_size(void) { return sizeof(bc_state_header) + sizeof(bc_snapshot); }

static void bc_serialize(const bc_snapshot *s, char *out) {
  bc_state_header head;
  memset(&head, 0, sizeof(head));
  memcpy(head.magic, "BCFMUST", 8);
  head.size = sizeof(bc_snapshot);
  head.token = bc_token_hash();
  memcpy(out, &head, sizeof(head));
  memcpy(out + sizeof(head), s, sizeof(bc_snapshot));
}

static int bc_deserialize(const char *in, size_t size, bc_snapshot *s, char *msg) {
  bc_state_header head;
  if (size != bc_serialized_size()) {
    snprintf(msg, BC_MSG, "serialized state has %zu bytes, expected %zu", size, bc_serialized_size());
    return 1;
  }
  memcpy(&head, in, sizeof(head));
  if (memcmp(head.magic, "BCFMUST", 8) || head.size != sizeof(bc_snapshot) || head.token != bc_token_hash()) {
    snprintf(msg, BC_MSG, "serialized state belongs to another model");
    return 1;
  }
  memcpy(s, in + sizeof(head), sizeof(bc_snapshot));
  return 0;
}

#endif
