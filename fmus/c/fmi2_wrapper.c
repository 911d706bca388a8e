/* bondcosim: the FMI 2.0 interface (Model Exchange and Co-Simulation) of a
   generated model.  One file for every model; the model comes in through
   "model.h" and "model_kernels.c", the version-independent logic through
   "bc_fmu_core.h".  Model Exchange is compiled in only when BC_HAS_ME. */
#include "bc_platform.h"   /* first: glibc symbol versions */
#include <stdlib.h>

#include "fmi2Functions.h"

#include "model.h"
#include "model_kernels.c"
#include "bc_fmu_core.h"

typedef struct {
  bc_snapshot s;
  fmi2Type type;
  int logging;
  fmi2CallbackLogger logger;
  fmi2ComponentEnvironment env;
  char name[128];
  char msg[BC_MSG];
} Instance;

/* The logger takes a printf format, but importers written in other languages
   (fmpy's Python callback) receive the format unformatted: pass the finished
   text as the format, with every '%' doubled. */
static void log_text(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name,
                     fmi2Status status, const char *text) {
  char escaped[2 * BC_MSG + 256];
  size_t k = 0;
  for (const char *c = text; *c && k + 2 < sizeof(escaped); ++c) {
    if (*c == '%') escaped[k++] = '%';
    escaped[k++] = *c;
  }
  escaped[k] = '\0';
  if (logger)
    logger(env, name, status, status == fmi2Warning ? "logStatusWarning"
           : status == fmi2Discard ? "logStatusDiscard" : "logStatusError", escaped);
}

static fmi2Status fail(Instance *m, fmi2Status status, const char *function) {
  char text[BC_MSG + 128];
  snprintf(text, sizeof(text), "%s: %s", function, m->msg);
  log_text(m->logger, m->env, m->name, status, text);
  return status;
}

static fmi2Status wrong_state(Instance *m, const char *function) {
  static const char *phases[] = {"instantiated", "initialization mode", "running", "terminated", "failed"};
  snprintf(m->msg, BC_MSG, "not allowed while the FMU is %s", phases[m->s.phase]);
  return fail(m, fmi2Error, function);
}

static fmi2Status unsupported(fmi2Component c, const char *function) {
  Instance *m = (Instance *)c;
  snprintf(m->msg, BC_MSG, "not supported by this FMU");
  return fail(m, fmi2Error, function);
}

/* A core result as a status: BC_DISCARD -> fmi2Discard, BC_ERROR -> fmi2Error (logged). */
static fmi2Status status_of(Instance *m, int r, const char *function) {
  return r == BC_OK ? fmi2OK : fail(m, r == BC_DISCARD ? fmi2Discard : fmi2Error, function);
}

#define INSTANCE Instance *m = (Instance *)c; if (!m) return fmi2Error
#define REQUIRE(cond, fn) if (!(cond)) return wrong_state(m, fn)
#define CHECK(call, fn) if (call) { return fail(m, fmi2Error, fn); }

/* -- common functions ----------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
  INSTANCE;
  (void)nCategories; (void)categories;
  m->logging = loggingOn;
  return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
  (void)fmuResourceLocation; (void)visible;
  fmi2CallbackLogger logger = functions ? functions->logger : NULL;
  fmi2ComponentEnvironment env = functions ? functions->componentEnvironment : NULL;
  const char *name = instanceName ? instanceName : "";
  char text[BC_MSG];
  if (!fmuGUID || strcmp(fmuGUID, BC_TOKEN) != 0) {
    snprintf(text, sizeof(text), "fmi2Instantiate: GUID %s does not match this FMU's %s",
             fmuGUID ? fmuGUID : "(null)", BC_TOKEN);
    log_text(logger, env, name, fmi2Error, text);
    return NULL;
  }
  if (fmuType == fmi2ModelExchange && !BC_HAS_ME) {
    snprintf(text, sizeof(text), "fmi2Instantiate: %s has held (sampled) variables and only "
             "offers Co-Simulation", BC_MODEL_NAME);
    log_text(logger, env, name, fmi2Error, text);
    return NULL;
  }
  Instance *m = (Instance *)calloc(1, sizeof(Instance));
  if (!m) return NULL;
  m->type = fmuType;
  m->logging = loggingOn;
  m->logger = logger;
  m->env = env;
  snprintf(m->name, sizeof(m->name), "%s", name);
  bc_reset(&m->s, 0.0);
  return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
  INSTANCE;
  (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
  REQUIRE(m->s.phase == BC_INSTANTIATED, "fmi2SetupExperiment");
  m->s.time = startTime;
  return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  INSTANCE;
  REQUIRE(m->s.phase == BC_INSTANTIATED, "fmi2EnterInitializationMode");
  m->s.phase = BC_INIT;
  m->s.dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  INSTANCE;
  REQUIRE(m->s.phase == BC_INIT, "fmi2ExitInitializationMode");
  if (bc_check_domain(&m->s, m->s.time, m->msg) || bc_refresh(&m->s, m->msg)
      || bc_check_outputs(&m->s, m->msg)) {
    m->s.phase = BC_FAILED;
    return fail(m, fmi2Error, "fmi2ExitInitializationMode");
  }
  m->s.phase = BC_RUNNING;
  return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
  INSTANCE;
  m->s.phase = BC_TERMINATED;
  return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
  INSTANCE;
  bc_reset(&m->s, 0.0);
  return fmi2OK;
}

/* -- variables: Real only ------------------------------------------------------------ */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
  INSTANCE;
  if (bc_get_real(&m->s, vr, nvr, value, m->msg)) return fail(m, fmi2Error, "fmi2GetReal");
  return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
  INSTANCE;
  REQUIRE(m->s.phase != BC_TERMINATED && m->s.phase != BC_FAILED, "fmi2SetReal");
  if (bc_set_real(&m->s, vr, nvr, value, m->msg)) return fail(m, fmi2Error, "fmi2SetReal");
  return fmi2OK;
}

#define NO_VARIABLES(fn, T, CONST)                                                        \
  fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, CONST T value[]) { \
    (void)vr; (void)value;                                                              \
    if (nvr == 0) return fmi2OK;                                                        \
    return unsupported(c, #fn " (the FMU has only Real variables)");                    \
  }
NO_VARIABLES(fmi2GetInteger, fmi2Integer, )
NO_VARIABLES(fmi2GetBoolean, fmi2Boolean, )
NO_VARIABLES(fmi2GetString, fmi2String, )
NO_VARIABLES(fmi2SetInteger, fmi2Integer, const)
NO_VARIABLES(fmi2SetBoolean, fmi2Boolean, const)
NO_VARIABLES(fmi2SetString, fmi2String, const)

/* -- FMU state ------------------------------------------------------------------------ */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
  INSTANCE;
  if (!*state) *state = malloc(sizeof(bc_snapshot));
  if (!*state) { snprintf(m->msg, BC_MSG, "out of memory"); return fail(m, fmi2Error, "fmi2GetFMUstate"); }
  memcpy(*state, &m->s, sizeof(bc_snapshot));
  return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
  INSTANCE;
  if (!state) { snprintf(m->msg, BC_MSG, "state is NULL"); return fail(m, fmi2Error, "fmi2SetFMUstate"); }
  memcpy(&m->s, state, sizeof(bc_snapshot));
  return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
  (void)c;
  if (state) { free(*state); *state = NULL; }
  return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
  (void)c; (void)state;
  *size = bc_serialized_size();
  return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte out[], size_t size) {
  INSTANCE;
  if (!state || size < bc_serialized_size()) {
    snprintf(m->msg, BC_MSG, "needs a state and %zu bytes, got %zu", bc_serialized_size(), size);
    return fail(m, fmi2Error, "fmi2SerializeFMUstate");
  }
  bc_serialize((const bc_snapshot *)state, out);
  return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte in[], size_t size, fmi2FMUstate *state) {
  INSTANCE;
  bc_snapshot *s = *state ? (bc_snapshot *)*state : (bc_snapshot *)malloc(sizeof(bc_snapshot));
  if (!s) { snprintf(m->msg, BC_MSG, "out of memory"); return fail(m, fmi2Error, "fmi2DeSerializeFMUstate"); }
  if (bc_deserialize(in, size, s, m->msg)) {
    if (!*state) free(s);
    return fail(m, fmi2Error, "fmi2DeSerializeFMUstate");
  }
  *state = s;
  return fmi2OK;
}

/* Partial derivatives of derivatives and outputs by states and inputs (bc_partials.h). */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
  INSTANCE;
  REQUIRE(m->s.phase != BC_INSTANTIATED, "fmi2GetDirectionalDerivative");
  return status_of(m, bc_directional(&m->s, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown,
                                     dvUnknown, m->msg), "fmi2GetDirectionalDerivative");
}

/* -- Model Exchange: states through the v[] array; event indicators locate the switches
   of the laws (bc_partials.h), event mode has nothing to update --------------------- */

fmi2Status fmi2EnterEventMode(fmi2Component c) { INSTANCE; (void)m; return fmi2OK; }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
  INSTANCE;
  (void)m;
  info->newDiscreteStatesNeeded = fmi2False;
  info->terminateSimulation = fmi2False;
  info->nominalsOfContinuousStatesChanged = fmi2False;
  info->valuesOfContinuousStatesChanged = fmi2False;
  info->nextEventTimeDefined = fmi2False;
  info->nextEventTime = 0.0;
  return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { INSTANCE; (void)m; return fmi2OK; }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
  INSTANCE;
  (void)noSetFMUStatePriorToCurrentPoint;
  *enterEventMode = fmi2False;
  *terminateSimulation = fmi2False;
  /* The integrator left the physical domain: Discard (FMI 2.0 sec. 2.1.3, "outside of
     its domain"), the FMU itself is fine and takes other states; an importer that
     cannot go back to a smaller step must stop, hence terminateSimulation. */
  int r = bc_me_evaluate(&m->s, m->msg);
  if (r) {
    *terminateSimulation = fmi2True;
    return fail(m, r == BC_DISCARD ? fmi2Discard : fmi2Error, "fmi2CompletedIntegratorStep");
  }
  return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
  INSTANCE;
  m->s.time = time;
  m->s.dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "got %zu states, the model has %d", nx, BC_NX);
                     return fail(m, fmi2Error, "fmi2SetContinuousStates"); }
  memcpy(m->s.v + BC_VR_X, x, sizeof(double) * nx);
  m->s.dirty = 1;
  return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "asked for %zu states, the model has %d", nx, BC_NX);
                     return fail(m, fmi2Error, "fmi2GetContinuousStates"); }
  memcpy(x, m->s.v + BC_VR_X, sizeof(double) * nx);
  return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "asked for %zu derivatives, the model has %d", nx, BC_NX);
                     return fail(m, fmi2Error, "fmi2GetDerivatives"); }
  int r = bc_me_evaluate(&m->s, m->msg);   /* Discard: outside the domain, try other states */
  memcpy(dx, m->s.v + BC_VR_DX, sizeof(double) * nx);
  if (r) return fail(m, r == BC_DISCARD ? fmi2Discard : fmi2Error, "fmi2GetDerivatives");
  return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real indicators[], size_t ni) {
  INSTANCE;
  return status_of(m, bc_event_indicators(&m->s, indicators, ni, m->msg), "fmi2GetEventIndicators");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nominals[], size_t nx) {
  INSTANCE;
  (void)m;
  for (size_t i = 0; i < nx && i < BC_NX; ++i) nominals[i] = bc_nominal[i];
  return fmi2OK;
}

/* -- Co-Simulation -------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
  (void)vr; (void)nvr; (void)order; (void)value;
  return unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
  (void)vr; (void)nvr; (void)order; (void)value;
  return unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
  INSTANCE;
  (void)noSetFMUStatePriorToCurrentPoint;
  REQUIRE(m->s.phase == BC_RUNNING, "fmi2DoStep");
  int r = bc_do_step(&m->s, currentCommunicationPoint, communicationStepSize, m->msg);
  /* Discard: the FMU is still at the step's start (fmi2LastSuccessfulTime) and may go on */
  if (r == BC_DISCARD) return fail(m, fmi2Discard, "fmi2DoStep");
  if (r) return fail(m, fmi2Error, "fmi2DoStep");
  return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
  INSTANCE;
  (void)m;
  if (s != fmi2DoStepStatus) return unsupported(c, "fmi2GetStatus (only fmi2DoStepStatus)");
  *value = fmi2OK;   /* doStep is synchronous: nothing is ever pending */
  return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
  INSTANCE;
  if (s != fmi2LastSuccessfulTime) return unsupported(c, "fmi2GetRealStatus (only fmi2LastSuccessfulTime)");
  *value = m->s.time;
  return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
  (void)s; (void)value;
  return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
  INSTANCE;
  (void)m;
  if (s != fmi2Terminated) return unsupported(c, "fmi2GetBooleanStatus (only fmi2Terminated)");
  *value = fmi2False;   /* after a Discard the FMU is at the step's start and may go on */
  return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
  (void)s; (void)value;
  return unsupported(c, "fmi2GetStringStatus");
}
