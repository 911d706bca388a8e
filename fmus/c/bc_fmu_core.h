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
  double h_adapt;     /* last step size of the variable-step solver, s (0: none yet) */
  int phase;
  int dirty;          /* derivatives and outputs are stale */
  struct { int guard; double value, time; } stage;   /* the guard an RK4 stage left (message) */
} bc_snapshot;

#define BC_MSG 512

static void bc_reset(bc_snapshot *s, double time) {
  memcpy(s->v, bc_start, sizeof(s->v));
  memcpy(s->z, bc_zinit, sizeof(s->z));
  s->time = time;
  s->h_adapt = 0.0;
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

/* Return codes of the core: OK, an error the FMU cannot recover from (or a
   caller's mistake), and a step discarded with the FMU left at its start. */
enum { BC_OK = 0, BC_ERROR = 1, BC_DISCARD = 2 };

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

/* States finite and every physical-domain guard (guard_row, declared by the
   model's elements) inside [bc_guard_min, bc_guard_max] at time t.  A NaN
   guard value fails too.  0 when all hold; else msg names the first failure. */
static int bc_check_domain(bc_snapshot *s, double t, char *msg) {
  double *v = s->v;
  for (int i = 0; i < BC_NX; ++i) {
    if (!isfinite(v[BC_VR_X + i])) {
      snprintf(msg, BC_MSG, "state %s = %g is not finite at t = %.17g s",
               bc_names[BC_VR_X + i], v[BC_VR_X + i], t);
      return 1;
    }
  }
#if BC_NG > 0
  double g[BC_NGA];
  guard_row(t, v + BC_VR_X, v + BC_VR_U, s->z, v + BC_VR_D, v + BC_VR_P, 0.0, g);
  for (int k = 0; k < BC_NG; ++k) {
    if (!(g[k] >= bc_guard_min[k] && g[k] <= bc_guard_max[k])) {
      snprintf(msg, BC_MSG, "%s = %.6g%s%s left its physical domain (%s) at t = %.17g s",
               bc_guard_names[k], g[k], bc_guard_units[k][0] ? " " : "", bc_guard_units[k],
               bc_guard_text[k], t);
      return 1;
    }
  }
#endif
  return 0;
}

#if BC_NG > 0
enum { BC_STAGE_LEFT = 16 };   /* bc_rk4 status: BC_STAGE_LEFT + k, guard k left at a stage */

/* BC_STAGE_CHECK of the RK4 kernel (model.h): 0 when the stage state (t, x, z) keeps
   every guard, else BC_STAGE_LEFT + the guard's index, with the guard, its value and
   the time kept in the instance's snapshot for the message.  bc_do_step passes the
   kernel p = s->v + BC_VR_P, and v is the snapshot's first member, so the snapshot is
   found from p (no global, no thread-local storage: those would need GLIBC_2.3). */
static int bc_stage_guard(double t, const double *x, const double *u, const double *z,
                          const double *d, const double *p) {
  double g[BC_NGA];
  guard_row(t, x, u, z, d, p, 0.0, g);
  for (int k = 0; k < BC_NG; ++k) {
    if (!(g[k] >= bc_guard_min[k] && g[k] <= bc_guard_max[k])) {
      bc_snapshot *s = (bc_snapshot *)(void *)(p - BC_VR_P);
      s->stage.guard = k;
      s->stage.value = g[k];
      s->stage.time = t;
      return BC_STAGE_LEFT + k;
    }
  }
  return 0;
}
#endif

/* Derivatives and outputs finite (after bc_refresh). */
static int bc_check_outputs(const bc_snapshot *s, char *msg) {
  for (int i = BC_VR_DX; i < BC_VR_DX + BC_NX; ++i) {
    if (!isfinite(s->v[i])) {
      snprintf(msg, BC_MSG, "%s = %g is not finite at t = %.17g s", bc_names[i], s->v[i], s->time);
      return 1;
    }
  }
  for (int i = BC_VR_Y; i < BC_VR_Y + BC_NY; ++i) {
    if (!isfinite(s->v[i])) {
      snprintf(msg, BC_MSG, "output %s = %g is not finite at t = %.17g s", bc_names[i], s->v[i], s->time);
      return 1;
    }
  }
  return 0;
}

/* Model Exchange: derivatives and outputs at the point the importer set (time,
   states, inputs), with the same checks as a Co-Simulation sub-step: states
   finite and inside every guard, the algebraic loops solved, derivatives and
   outputs finite.  BC_OK; BC_DISCARD where the point is outside the model's
   domain but the FMU is fine -- the importer may set other states (a smaller
   integrator step, FMI 2.0 sec. 2.1.3 / FMI 3.0 sec. 2.2.3 "Discard"); the
   values are still written.  Before initialisation ends nothing is checked. */
static int bc_me_evaluate(bc_snapshot *s, char *msg) {
  if (s->phase != BC_RUNNING) return bc_refresh(s, msg) ? BC_ERROR : BC_OK;
  if (bc_check_states(s, msg) || bc_refresh(s, msg) || bc_check_domain(s, s->time, msg)
      || bc_check_outputs(s, msg))
    return BC_DISCARD;
  return BC_OK;
}

#include "bc_adaptive.h"   /* bc_dopri: the variable-step solver */
#include "bc_partials.h"   /* event indicators, directional derivatives */

/* Co-simulation step.  solver = 1: bc_dopri (variable step).  solver = 0:
   classic RK4 in m equal sub-steps no longer than the
   solver step, inputs held, held variables updated at each sub-step start
   (bc_rk4, one sub-step per call so that the domain is checked after each;
   its stage states are checked too, bc_stage_guard: a sub-step can jump
   across a region where the model is undefined and land inside the domain
   again -- a chamber volume through zero -- with every end point fine).
   m is computed in double and bounded by max_substeps: a step that needs
   more is discarded before any work, never an int overflow or a hang.
   BC_DISCARD (the state restored to the step's start, msg naming the cause):
   too many sub-steps, a failed algebraic loop, a non-finite state or output,
   a guard left.  BC_ERROR: a step that does not start where the FMU is, or
   a non-positive H. */
static int bc_do_step(bc_snapshot *s, double t, double H, char *msg) {
  if (!(H > 0.0) || !isfinite(H)) {
    snprintf(msg, BC_MSG, "communication step %g s is not positive", H);
    return BC_ERROR;
  }
  double tol = 1e-9 * (fabs(s->time) > 1.0 ? fabs(s->time) : 1.0);
  if (fabs(t - s->time) > tol) {
    snprintf(msg, BC_MSG, "doStep from t = %.17g s, but the FMU is at t = %.17g s", t, s->time);
    return BC_ERROR;
  }
  if (s->v[BC_VR_SOLVER] != 0.0) {   /* variable-step Dormand-Prince (bc_adaptive.h) */
    bc_snapshot old = *s;
    if (bc_dopri(s, t, H, msg)) { *s = old; return BC_DISCARD; }
    s->time = t + H;
    s->dirty = 1;
    if (bc_refresh(s, msg) || bc_check_outputs(s, msg)) { *s = old; return BC_DISCARD; }
    return BC_OK;
  }
  double hmax = s->v[BC_VR_STEP], maxsub = s->v[BC_VR_MAXSUB];
  double md = ceil(H / hmax - 1e-9);   /* double: no overflow above 2^31 */
  if (!(md >= 1.0)) md = 1.0;
  if (!(md <= maxsub)) {
    snprintf(msg, BC_MSG, "doStep of H = %g s from t = %.17g s needs %.4g sub-steps of at most "
             "solver_step = %g s, more than max_substeps = %.4g; take shorter communication "
             "steps, or set solver_step / max_substeps before initialisation", H, t, md, hmax, maxsub);
    return BC_DISCARD;
  }
  long long m = (long long)md;
  double h = H / m;
  bc_snapshot old = *s;
  double *v = s->v;
  for (long long j = 0; j < m; ++j) {
    int status = 0;
    /* t + j h as bc_rk4(.., m, ..) computes it: the same numbers as bondgraph.simulate */
    int bad = bc_rk4(1, t + j * h, h, 1, v + BC_VR_X, v + BC_VR_U, 0, s->z, bc_zinit, v + BC_VR_D,
                     v + BC_VR_P, 0, &status);
    if (bad) {
#if BC_NG > 0
      if (bad > 0 && status >= BC_STAGE_LEFT) {   /* a stage between two sub-step ends */
        int k = s->stage.guard;
        snprintf(msg, BC_MSG, "%s = %.6g%s%s left its physical domain (%s) at an RK4 stage at "
                 "t = %.17g s, inside the sub-step from t = %.17g s", bc_guard_names[k],
                 s->stage.value, bc_guard_units[k][0] ? " " : "", bc_guard_units[k],
                 bc_guard_text[k], s->stage.time, t + j * h);
        *s = old;
        return BC_DISCARD;
      }
#endif
      *s = old;
      snprintf(msg, BC_MSG, "step from t = %.17g s failed at t = %.17g s: %s", t, t + j * h,
               bad < 0 ? "out of memory" : bc_newton_messages[status > 0 && status < 4 ? status : 0]);
      return bad < 0 ? BC_ERROR : BC_DISCARD;
    }
    if (bc_check_domain(s, t + (j + 1) * h, msg)) { *s = old; return BC_DISCARD; }
  }
  s->time = t + H;
  s->dirty = 1;
  if (bc_refresh(s, msg) || bc_check_outputs(s, msg)) { *s = old; return BC_DISCARD; }
  return BC_OK;
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

/* Set values: every one finite and inside the variable's declared [min, max]
   (a NaN input, a negative mass), the solver step > 0, max_substeps >= 1;
   otherwise nothing is set and msg names the variable and the value. */
static int bc_set_real(bc_snapshot *s, const unsigned *vr, size_t n, const double *value, char *msg) {
  for (size_t i = 0; i < n; ++i) {
    if (!bc_settable(s, vr[i], msg)) return 1;
    const char *name = bc_names[vr[i]];
    if (!isfinite(value[i])) {
      snprintf(msg, BC_MSG, "%s = %g rejected: not a finite number (%s keeps %.17g)",
               name, value[i], name, s->v[vr[i]]);
      return 1;
    }
    if ((vr[i] == BC_VR_STEP && !(value[i] > 0.0)) || (vr[i] == BC_VR_MAXSUB && !(value[i] >= 1.0))
        || (vr[i] == BC_VR_TOL && !(value[i] > 0.0))) {
      snprintf(msg, BC_MSG, "%s must be %s, got %g", name,
               vr[i] == BC_VR_MAXSUB ? "at least 1" : "positive", value[i]);
      return 1;
    }
    if (vr[i] == BC_VR_SOLVER && value[i] != 0.0 && !(value[i] == 1.0 && BC_ND == 0)) {
      snprintf(msg, BC_MSG, "solver = %g rejected: 0 (fixed-step RK4) or 1 (variable-step "
               "Dormand-Prince%s)", value[i], BC_ND ? "; not for this model, whose held "
               "variables need the fixed step" : "");
      return 1;
    }
    if (value[i] < bc_min[vr[i]] || value[i] > bc_max[vr[i]]) {
      snprintf(msg, BC_MSG, "%s = %.17g rejected: outside its declared range [%g, %g]",
               name, value[i], bc_min[vr[i]], bc_max[vr[i]]);
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
