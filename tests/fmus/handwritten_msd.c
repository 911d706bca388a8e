/* A hand-written FMI 2.0 Co-Simulation FMU: mass-spring-damper.
 *
 * "An FMU we did not generate": it shares no code with fmus/, so the co-simulation master is
 * tested against an FMU written the way a third-party tool would write it.
 *
 *   m x'' + c x' + k x = F,   x(0) = x0, v(0) = v0
 *
 * input F [N]; outputs x [m], v [m/s] (no direct feedthrough); parameters m [kg], k [N/m],
 * c [N.s/m], x0 [m], v0 [m/s].  doStep(t, H) integrates with classic RK4 in n = ceil(H / 1e-4)
 * equal sub-steps, F held.  Every fmi2 function exists (fmpy binds them all); the Model Exchange
 * ones and state serialisation return fmi2Error.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"

#define GUID "{8c4e810f-3df3-4a00-8276-176fa3c9d2a0}"
#define H_MAX 1e-4

enum { VR_F, VR_X, VR_V, VR_M, VR_K, VR_C, VR_X0, VR_V0, N_VR };
static const char *const NAMES[N_VR] = {"F", "x", "v", "m", "k", "c", "x0", "v0"};

typedef enum { INSTANTIATED, INITIALIZING, STEPPING, TERMINATED } Mode;

typedef struct {
    double r[N_VR];   /* indexed by value reference */
    double time;
    Mode mode;
} State;

typedef struct {
    State s;
    char name[64];
    fmi2CallbackFunctions cb;
} Instance;

static void logmsg(Instance *in, fmi2Status status, const char *msg) {
    /* the message holds no printf directives: it is passed as the format */
    if (in->cb.logger) in->cb.logger(in->cb.componentEnvironment, in->name, status, "log", msg);
}

static fmi2Status fail(Instance *in, const char *msg) {
    logmsg(in, fmi2Error, msg);
    return fmi2Error;
}

/* ---- model ------------------------------------------------------------------------------- */
static void rhs(const double *r, double x, double v, double *dx, double *dv) {
    *dx = v;
    *dv = (r[VR_F] - r[VR_K] * x - r[VR_C] * v) / r[VR_M];
}

static void rk4(double *r, double h) {
    double x = r[VR_X], v = r[VR_V], k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
    rhs(r, x, v, &k1x, &k1v);
    rhs(r, x + 0.5 * h * k1x, v + 0.5 * h * k1v, &k2x, &k2v);
    rhs(r, x + 0.5 * h * k2x, v + 0.5 * h * k2v, &k3x, &k3v);
    rhs(r, x + h * k3x, v + h * k3v, &k4x, &k4v);
    r[VR_X] = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    r[VR_V] = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

/* ---- common functions -------------------------------------------------------------------- */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)resources; (void)visible; (void)loggingOn;
    if (!cb || !cb->allocateMemory || !cb->freeMemory) return NULL;
    if (type != fmi2CoSimulation || !guid || strcmp(guid, GUID) != 0) {
        if (cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "log",
                                   "wrong fmuType or GUID: only Co-Simulation of this GUID");
        return NULL;
    }
    Instance *in = cb->allocateMemory(1, sizeof(Instance));
    if (!in) return NULL;
    in->cb = *cb;
    snprintf(in->name, sizeof in->name, "%s", name ? name : "msd");
    const double start[N_VR] = {0.0, 0.0, 0.0, 1.0, 100.0, 2.0, 0.0, 0.0};
    memcpy(in->s.r, start, sizeof start);
    in->s.mode = INSTANTIATED;
    return in;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *in = c;
    if (in) in->cb.freeMemory(in);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stopDef, fmi2Real stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Instance *)c)->s.time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *in = c;
    if (in->s.mode != INSTANTIATED) return fail(in, "enterInitializationMode: not instantiated");
    in->s.mode = INITIALIZING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *in = c;
    if (in->s.mode != INITIALIZING) return fail(in, "exitInitializationMode: not initializing");
    if (!(in->s.r[VR_M] > 0.0)) return fail(in, "parameter m must be positive");
    in->s.r[VR_X] = in->s.r[VR_X0];
    in->s.r[VR_V] = in->s.r[VR_V0];
    in->s.mode = STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ((Instance *)c)->s.mode = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *in = c;
    const double start[N_VR] = {0.0, 0.0, 0.0, 1.0, 100.0, 2.0, 0.0, 0.0};
    memcpy(in->s.r, start, sizeof start);
    in->s.mode = INSTANTIATED;
    return fmi2OK;
}

/* ---- values ------------------------------------------------------------------------------ */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Instance *in = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VR) return fail(in, "getReal: unknown value reference");
        unsigned j = vr[i];
        if (in->s.mode < STEPPING && (j == VR_X || j == VR_V)) j = (j == VR_X) ? VR_X0 : VR_V0;
        v[i] = in->s.r[j];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    Instance *in = c;
    char msg[96];
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= N_VR) return fail(in, "setReal: unknown value reference");
        if (vr[i] == VR_X || vr[i] == VR_V) {
            snprintf(msg, sizeof msg, "setReal: %s is a calculated output", NAMES[vr[i]]);
            return fail(in, msg);
        }
        if (vr[i] != VR_F && in->s.mode >= STEPPING) {
            snprintf(msg, sizeof msg, "setReal: parameter %s is fixed after initialization",
                     NAMES[vr[i]]);
            return fail(in, msg);
        }
        in->s.r[vr[i]] = v[i];
    }
    return fmi2OK;
}

#define NO_VALUES(fn, T) \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t n, T v[]) { \
        (void)vr; (void)v; \
        return n == 0 ? fmi2OK : fail(c, #fn ": the FMU has only Real variables"); }
NO_VALUES(fmi2GetInteger, fmi2Integer)
NO_VALUES(fmi2GetBoolean, fmi2Boolean)
NO_VALUES(fmi2GetString, fmi2String)
NO_VALUES(fmi2SetInteger, const fmi2Integer)
NO_VALUES(fmi2SetBoolean, const fmi2Boolean)
NO_VALUES(fmi2SetString, const fmi2String)

/* ---- FMU state (rollback) ---------------------------------------------------------------- */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Instance *in = c;
    if (!*state) *state = in->cb.allocateMemory(1, sizeof(State));
    if (!*state) return fail(in, "getFMUstate: out of memory");
    memcpy(*state, &in->s, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    if (!state) return fail(c, "setFMUstate: null state");
    memcpy(&((Instance *)c)->s, state, sizeof(State));
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    if (state && *state) ((Instance *)c)->cb.freeMemory(*state);
    if (state) *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)s; (void)size;
    return fail(c, "serialization is not supported");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)s; (void)b; (void)n;
    return fail(c, "serialization is not supported");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n,
                                   fmi2FMUstate *s) {
    (void)b; (void)n; (void)s;
    return fail(c, "serialization is not supported");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference k[], size_t nk,
                                        const fmi2Real dk[], fmi2Real du[]) {
    (void)u; (void)nu; (void)k; (void)nk; (void)dk; (void)du;
    return fail(c, "directional derivatives are not supported");
}

/* ---- Model Exchange: not offered ---------------------------------------------------------- */
#define NOT_ME(c) return fail(c, "this FMU offers Co-Simulation only")
fmi2Status fmi2EnterEventMode(fmi2Component c) { NOT_ME(c); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e) { (void)e; NOT_ME(c); }
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { NOT_ME(c); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean p, fmi2Boolean *e,
                                       fmi2Boolean *t) { (void)p; (void)e; (void)t; NOT_ME(c); }
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { (void)t; NOT_ME(c); }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    (void)x; (void)n; NOT_ME(c); }
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real d[], size_t n) { (void)d; (void)n; NOT_ME(c); }
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
    (void)z; (void)n; NOT_ME(c); }
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    (void)x; (void)n; NOT_ME(c); }
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    (void)x; (void)n; NOT_ME(c); }

/* ---- Co-Simulation ------------------------------------------------------------------------ */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer o[], const fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    return fail(c, "input derivatives are not supported");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer o[], fmi2Real v[]) {
    (void)vr; (void)n; (void)o; (void)v;
    return fail(c, "output derivatives are not supported");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real H, fmi2Boolean noSetPrior) {
    Instance *in = c;
    (void)noSetPrior;
    if (in->s.mode != STEPPING) return fail(in, "doStep: not initialized");
    if (!(H > 0.0)) return fail(in, "doStep: the step size must be positive");
    if (fabs(t - in->s.time) > 1e-9 * (1.0 + fabs(t)))
        return fail(in, "doStep: currentCommunicationPoint is not the FMU's time");
    const long n = (long)ceil(H / H_MAX * (1.0 - 1e-12));
    const double h = H / (double)n;
    double saved[N_VR];
    memcpy(saved, in->s.r, sizeof saved);
    for (long i = 0; i < n; i++) rk4(in->s.r, h);
    if (!isfinite(in->s.r[VR_X]) || !isfinite(in->s.r[VR_V])) {
        memcpy(in->s.r, saved, sizeof saved);
        return fail(in, "doStep: the state became non-finite");
    }
    in->s.time = t + H;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { return fail(c, "cancelStep: steps are synchronous"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)s; (void)v;
    return fail(c, "getStatus: steps are synchronous");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    Instance *in = c;
    if (s != fmi2LastSuccessfulTime) return fail(in, "getRealStatus: unsupported kind");
    *v = in->s.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)s; (void)v;
    return fail(c, "getIntegerStatus: unsupported");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    (void)s; (void)v;
    return fail(c, "getBooleanStatus: unsupported");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    (void)s; (void)v;
    return fail(c, "getStringStatus: unsupported");
}
