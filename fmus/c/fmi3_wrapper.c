/* bondcosim: the FMI 3.0 interface (Model Exchange and Co-Simulation) of a
   generated model.  One file for every model; the model comes in through
   "model.h" and "model_kernels.c", the version-independent logic through
   "bc_fmu_core.h".  Model Exchange is compiled in only when BC_HAS_ME.

   Every variable is a Float64 scalar; FMI 3.0 adds "time" (value reference
   BC_VR_TIME, read-only, not part of v[]) and one variable per event indicator
   after it (calculated).  No clocks, intermediate updates or early return:
   Co-Simulation never asks for Event Mode; in Model Exchange the event
   indicators locate the laws' switches and event mode has nothing to update.
   Every function of fmi3Functions.h is defined (importers bind them all);
   those the FMU does not support return fmi3Error with a logged message. */
#include "bc_platform.h"   /* first: glibc symbol versions */
#include <stdlib.h>

#include "fmi3Functions.h"

#include "model.h"
#include "model_kernels.c"
#include "bc_fmu_core.h"

typedef enum { BC_ME, BC_CS } bc_interface;

typedef struct {
  bc_snapshot s;
  bc_interface type;
  int logging;
  fmi3LogMessageCallback logger;
  fmi3InstanceEnvironment env;
  char name[128];
  char msg[BC_MSG];
} Instance;

/* FMI 3.0 loggers take a finished string (no printf format) and no instance
   name: the name leads the text. */
static void log_text(fmi3LogMessageCallback logger, fmi3InstanceEnvironment env, const char *name,
                     fmi3Status status, const char *function, const char *text) {
  char line[BC_MSG + 256];
  if (!logger) return;
  snprintf(line, sizeof(line), "%s%s%s: %s", name, *name ? ": " : "", function, text);
  logger(env, status, status == fmi3Warning ? "logStatusWarning"
         : status == fmi3Discard ? "logStatusDiscard" : "logStatusError", line);
}

static fmi3Status fail(Instance *m, fmi3Status status, const char *function) {
  log_text(m->logger, m->env, m->name, status, function, m->msg);
  return status;
}

static fmi3Status wrong_state(Instance *m, const char *function) {
  static const char *phases[] = {"instantiated", "initialization mode", "running", "terminated", "failed"};
  snprintf(m->msg, BC_MSG, "not allowed while the FMU is %s", phases[m->s.phase]);
  return fail(m, fmi3Error, function);
}

static fmi3Status unsupported(fmi3Instance c, const char *function) {
  Instance *m = (Instance *)c;
  if (!m) return fmi3Error;
  snprintf(m->msg, BC_MSG, "not supported by this FMU");
  return fail(m, fmi3Error, function);
}

/* A core result as a status: BC_DISCARD -> fmi3Discard, BC_ERROR -> fmi3Error (logged). */
static fmi3Status status_of(Instance *m, int r, const char *function) {
  return r == BC_OK ? fmi3OK : fail(m, r == BC_DISCARD ? fmi3Discard : fmi3Error, function);
}

#define INSTANCE Instance *m = (Instance *)c; if (!m) return fmi3Error
#define REQUIRE(cond, fn) if (!(cond)) return wrong_state(m, fn)
#define CHECK(call, fn) if (call) { return fail(m, fmi3Error, fn); }

/* -- common functions ----------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
  INSTANCE;
  (void)nCategories; (void)categories;
  m->logging = loggingOn;
  return fmi3OK;
}

static Instance *instantiate(const char *function, bc_interface type, fmi3String instanceName,
                             fmi3String token, fmi3Boolean loggingOn,
                             fmi3InstanceEnvironment env, fmi3LogMessageCallback logger) {
  const char *name = instanceName ? instanceName : "";
  char text[BC_MSG];
  if (!token || strcmp(token, BC_TOKEN) != 0) {
    snprintf(text, sizeof(text), "instantiation token %s does not match this FMU's %s",
             token ? token : "(null)", BC_TOKEN);
    log_text(logger, env, name, fmi3Error, function, text);
    return NULL;
  }
  if (type == BC_ME && !BC_HAS_ME) {
    snprintf(text, sizeof(text), "%s has held (sampled) variables and only offers Co-Simulation",
             BC_MODEL_NAME);
    log_text(logger, env, name, fmi3Error, function, text);
    return NULL;
  }
  Instance *m = (Instance *)calloc(1, sizeof(Instance));
  if (!m) return NULL;
  m->type = type;
  m->logging = loggingOn;
  m->logger = logger;
  m->env = env;
  snprintf(m->name, sizeof(m->name), "%s", name);
  bc_reset(&m->s, 0.0);
  return m;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
  (void)resourcePath; (void)visible;
  return instantiate("fmi3InstantiateModelExchange", BC_ME, instanceName, instantiationToken,
                     loggingOn, instanceEnvironment, logMessage);
}

/* Event mode is never needed (no events) and steps never return early, so
   eventModeUsed and earlyReturnAllowed change nothing; there are no
   intermediate variables to update. */
fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
  (void)resourcePath; (void)visible; (void)eventModeUsed; (void)earlyReturnAllowed;
  (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
  return instantiate("fmi3InstantiateCoSimulation", BC_CS, instanceName, instantiationToken,
                     loggingOn, instanceEnvironment, logMessage);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
  (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
  (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
  log_text(logMessage, instanceEnvironment, instanceName ? instanceName : "", fmi3Error,
           "fmi3InstantiateScheduledExecution",
           "Scheduled Execution is not supported (Model Exchange and Co-Simulation are)");
  return NULL;
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined,
                                       fmi3Float64 stopTime) {
  INSTANCE;
  (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
  REQUIRE(m->s.phase == BC_INSTANTIATED, "fmi3EnterInitializationMode");
  m->s.time = startTime;
  m->s.phase = BC_INIT;
  m->s.dirty = 1;
  return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
  INSTANCE;
  REQUIRE(m->s.phase == BC_INIT, "fmi3ExitInitializationMode");
  if (bc_check_domain(&m->s, m->s.time, m->msg) || bc_refresh(&m->s, m->msg)
      || bc_check_outputs(&m->s, m->msg)) {
    m->s.phase = BC_FAILED;
    return fail(m, fmi3Error, "fmi3ExitInitializationMode");
  }
  m->s.phase = BC_RUNNING;
  return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { INSTANCE; (void)m; return fmi3OK; }

fmi3Status fmi3Terminate(fmi3Instance c) {
  INSTANCE;
  m->s.phase = BC_TERMINATED;
  return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance c) {
  INSTANCE;
  bc_reset(&m->s, 0.0);
  return fmi3OK;
}

/* -- variables: Float64 only ---------------------------------------------------- */

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
  INSTANCE;
  if (nValues != nvr) {
    snprintf(m->msg, BC_MSG, "%zu values for %zu scalar variables", nValues, nvr);
    return fail(m, fmi3Error, "fmi3GetFloat64");
  }
  for (size_t i = 0; i < nvr; ++i) {   /* outputs are refreshed once, on the first */
    if (vr[i] == BC_VR_TIME) values[i] = m->s.time;
    else if (vr[i] > BC_VR_TIME && vr[i] <= BC_VR_TIME + BC_NEI) {   /* event indicator variables */
      double z[BC_NEI > 0 ? BC_NEI : 1];
      int r = bc_event_indicators(&m->s, z, BC_NEI, m->msg);
      if (r) return status_of(m, r, "fmi3GetFloat64");
      values[i] = z[vr[i] - BC_VR_TIME - 1];
    }
    else CHECK(bc_get_real(&m->s, vr + i, 1, values + i, m->msg), "fmi3GetFloat64");
  }
  return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
  INSTANCE;
  REQUIRE(m->s.phase != BC_TERMINATED && m->s.phase != BC_FAILED, "fmi3SetFloat64");
  if (nValues != nvr) {
    snprintf(m->msg, BC_MSG, "%zu values for %zu scalar variables", nValues, nvr);
    return fail(m, fmi3Error, "fmi3SetFloat64");
  }
  for (size_t i = 0; i < nvr; ++i) {
    if (vr[i] == BC_VR_TIME) {
      snprintf(m->msg, BC_MSG, "time is the independent variable and cannot be set");
      return fail(m, fmi3Error, "fmi3SetFloat64");
    }
    if (vr[i] > BC_VR_TIME && vr[i] <= BC_VR_TIME + BC_NEI) {
      snprintf(m->msg, BC_MSG, "event indicator %u is calculated by the FMU and cannot be set",
               vr[i] - BC_VR_TIME);
      return fail(m, fmi3Error, "fmi3SetFloat64");
    }
  }
  CHECK(bc_set_real(&m->s, vr, nvr, values, m->msg), "fmi3SetFloat64");
  return fmi3OK;
}

static fmi3Status no_variables(fmi3Instance c, size_t nvr, const char *function) {
  if (nvr == 0) return fmi3OK;
  INSTANCE;
  snprintf(m->msg, BC_MSG, "the FMU has only Float64 variables");
  return fail(m, fmi3Error, function);
}

#define NO_VARIABLES(fn, T, CONST)                                                          \
  fmi3Status fn(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, CONST T values[], \
                size_t nValues) {                                                          \
    (void)vr; (void)values; (void)nValues;                                                 \
    return no_variables(c, nvr, #fn);                                                      \
  }
NO_VARIABLES(fmi3GetFloat32, fmi3Float32, )
NO_VARIABLES(fmi3GetInt8, fmi3Int8, )
NO_VARIABLES(fmi3GetUInt8, fmi3UInt8, )
NO_VARIABLES(fmi3GetInt16, fmi3Int16, )
NO_VARIABLES(fmi3GetUInt16, fmi3UInt16, )
NO_VARIABLES(fmi3GetInt32, fmi3Int32, )
NO_VARIABLES(fmi3GetUInt32, fmi3UInt32, )
NO_VARIABLES(fmi3GetInt64, fmi3Int64, )
NO_VARIABLES(fmi3GetUInt64, fmi3UInt64, )
NO_VARIABLES(fmi3GetBoolean, fmi3Boolean, )
NO_VARIABLES(fmi3GetString, fmi3String, )
NO_VARIABLES(fmi3SetFloat32, fmi3Float32, const)
NO_VARIABLES(fmi3SetInt8, fmi3Int8, const)
NO_VARIABLES(fmi3SetUInt8, fmi3UInt8, const)
NO_VARIABLES(fmi3SetInt16, fmi3Int16, const)
NO_VARIABLES(fmi3SetUInt16, fmi3UInt16, const)
NO_VARIABLES(fmi3SetInt32, fmi3Int32, const)
NO_VARIABLES(fmi3SetUInt32, fmi3UInt32, const)
NO_VARIABLES(fmi3SetInt64, fmi3Int64, const)
NO_VARIABLES(fmi3SetUInt64, fmi3UInt64, const)
NO_VARIABLES(fmi3SetBoolean, fmi3Boolean, const)
NO_VARIABLES(fmi3SetString, fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
  (void)vr; (void)valueSizes; (void)values; (void)nValues;
  return no_variables(c, nvr, "fmi3GetBinary");
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
  (void)vr; (void)valueSizes; (void)values; (void)nValues;
  return no_variables(c, nvr, "fmi3SetBinary");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
  (void)valueReference; (void)nDependencies;
  return unsupported(c, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
  (void)dependent; (void)elementIndicesOfDependent; (void)independents;
  (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
  return unsupported(c, "fmi3GetVariableDependencies");
}

/* -- FMU state ------------------------------------------------------------------------ */

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *state) {
  INSTANCE;
  if (!*state) *state = malloc(sizeof(bc_snapshot));
  if (!*state) { snprintf(m->msg, BC_MSG, "out of memory"); return fail(m, fmi3Error, "fmi3GetFMUState"); }
  memcpy(*state, &m->s, sizeof(bc_snapshot));
  return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState state) {
  INSTANCE;
  if (!state) { snprintf(m->msg, BC_MSG, "state is NULL"); return fail(m, fmi3Error, "fmi3SetFMUState"); }
  memcpy(&m->s, state, sizeof(bc_snapshot));
  return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *state) {
  (void)c;
  if (state) { free(*state); *state = NULL; }
  return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState state, size_t *size) {
  (void)c; (void)state;
  *size = bc_serialized_size();
  return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState state, fmi3Byte out[], size_t size) {
  INSTANCE;
  if (!state || size < bc_serialized_size()) {
    snprintf(m->msg, BC_MSG, "needs a state and %zu bytes, got %zu", bc_serialized_size(), size);
    return fail(m, fmi3Error, "fmi3SerializeFMUState");
  }
  bc_serialize((const bc_snapshot *)state, (char *)out);
  return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte in[], size_t size, fmi3FMUState *state) {
  INSTANCE;
  bc_snapshot *s = *state ? (bc_snapshot *)*state : (bc_snapshot *)malloc(sizeof(bc_snapshot));
  if (!s) { snprintf(m->msg, BC_MSG, "out of memory"); return fail(m, fmi3Error, "fmi3DeserializeFMUState"); }
  if (bc_deserialize((const char *)in, size, s, m->msg)) {
    if (!*state) free(s);
    return fail(m, fmi3Error, "fmi3DeserializeFMUState");
  }
  *state = s;
  return fmi3OK;
}

/* -- partial derivatives: directional (bc_partials.h), not adjoint ---------------------- */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
  INSTANCE;
  REQUIRE(m->s.phase != BC_INSTANTIATED, "fmi3GetDirectionalDerivative");
  if (nSeed != nKnowns || nSensitivity != nUnknowns) {
    snprintf(m->msg, BC_MSG, "%zu seeds for %zu knowns, %zu sensitivities for %zu unknowns "
             "(all scalar)", nSeed, nKnowns, nSensitivity, nUnknowns);
    return fail(m, fmi3Error, "fmi3GetDirectionalDerivative");
  }
  return status_of(m, bc_directional(&m->s, unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity,
                                     m->msg), "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
  (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
  (void)sensitivity; (void)nSensitivity;
  return unsupported(c, "fmi3GetAdjointDerivative");
}

/* -- configuration mode, clocks, intervals, shifts: none ------------------------------- */

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3EnterConfigurationMode"); }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { return unsupported(c, "fmi3ExitConfigurationMode"); }

/* The FMU has no clocks: calls about zero of them succeed, any other fails. */
static fmi3Status no_clocks(fmi3Instance c, size_t nvr, const char *function) {
  if (nvr == 0) return fmi3OK;
  INSTANCE;
  snprintf(m->msg, BC_MSG, "the FMU has no clocks");
  return fail(m, fmi3Error, function);
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
  (void)vr; (void)values;
  return no_clocks(c, nvr, "fmi3GetClock");
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
  (void)vr; (void)values;
  return no_clocks(c, nvr, "fmi3SetClock");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
  (void)vr; (void)intervals; (void)qualifiers;
  return no_clocks(c, nvr, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
  (void)vr; (void)counters; (void)resolutions; (void)qualifiers;
  return no_clocks(c, nvr, "fmi3GetIntervalFraction");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[]) {
  (void)vr; (void)shifts;
  return no_clocks(c, nvr, "fmi3GetShiftDecimal");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
  (void)vr; (void)counters; (void)resolutions;
  return no_clocks(c, nvr, "fmi3GetShiftFraction");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
  (void)vr; (void)intervals;
  return no_clocks(c, nvr, "fmi3SetIntervalDecimal");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
  (void)vr; (void)counters; (void)resolutions;
  return no_clocks(c, nvr, "fmi3SetIntervalFraction");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
  (void)vr; (void)shifts;
  return no_clocks(c, nvr, "fmi3SetShiftDecimal");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
  (void)vr; (void)counters; (void)resolutions;
  return no_clocks(c, nvr, "fmi3SetShiftFraction");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
  (void)clockReference; (void)activationTime;
  return unsupported(c, "fmi3ActivateModelPartition (Scheduled Execution)");
}

/* -- event mode: nothing ever happens -------------------------------------------------- */

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { INSTANCE; (void)m; return fmi3OK; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
  INSTANCE;
  (void)m;
  if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
  if (terminateSimulation) *terminateSimulation = fmi3False;
  if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
  if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
  if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
  if (nextEventTime) *nextEventTime = 0.0;
  return fmi3OK;
}

/* -- Model Exchange: states through the v[] array; event indicators locate the switches
   of the laws (bc_partials.h), event mode has nothing to update --------------------- */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { INSTANCE; (void)m; return fmi3OK; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
  INSTANCE;
  (void)noSetFMUStatePriorToCurrentPoint;
  *enterEventMode = fmi3False;
  *terminateSimulation = fmi3False;
  /* The integrator left the physical domain: Discard (FMI 3.0 sec. 2.2.3), the FMU
     itself is fine and takes other states; an importer that cannot go back to a
     smaller step must stop, hence terminateSimulation. */
  int r = bc_me_evaluate(&m->s, m->msg);
  if (r) {
    *terminateSimulation = fmi3True;
    return fail(m, r == BC_DISCARD ? fmi3Discard : fmi3Error, "fmi3CompletedIntegratorStep");
  }
  return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 time) {
  INSTANCE;
  m->s.time = time;
  m->s.dirty = 1;
  return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "got %zu states, the model has %d", nx, BC_NX);
                     return fail(m, fmi3Error, "fmi3SetContinuousStates"); }
  memcpy(m->s.v + BC_VR_X, x, sizeof(double) * nx);
  m->s.dirty = 1;
  return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "asked for %zu states, the model has %d", nx, BC_NX);
                     return fail(m, fmi3Error, "fmi3GetContinuousStates"); }
  memcpy(x, m->s.v + BC_VR_X, sizeof(double) * nx);
  return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx) {
  INSTANCE;
  if (nx != BC_NX) { snprintf(m->msg, BC_MSG, "asked for %zu derivatives, the model has %d", nx, BC_NX);
                     return fail(m, fmi3Error, "fmi3GetContinuousStateDerivatives"); }
  int r = bc_me_evaluate(&m->s, m->msg);   /* Discard: outside the domain, try other states */
  memcpy(dx, m->s.v + BC_VR_DX, sizeof(double) * nx);
  if (r) return fail(m, r == BC_DISCARD ? fmi3Discard : fmi3Error, "fmi3GetContinuousStateDerivatives");
  return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 indicators[], size_t ni) {
  INSTANCE;
  return status_of(m, bc_event_indicators(&m->s, indicators, ni, m->msg), "fmi3GetEventIndicators");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[], size_t nx) {
  INSTANCE;
  (void)m;
  for (size_t i = 0; i < nx && i < BC_NX; ++i) nominals[i] = bc_nominal[i];
  return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) {
  INSTANCE;
  (void)m;
  *n = BC_NEI;
  return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) {
  INSTANCE;
  (void)m;
  *n = BC_NX;
  return fmi3OK;
}

/* -- Co-Simulation -------------------------------------------------------------------- */

fmi3Status fmi3EnterStepMode(fmi3Instance c) { INSTANCE; (void)m; return fmi3OK; }

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
  (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues;
  return unsupported(c, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
  INSTANCE;
  (void)noSetFMUStatePriorToCurrentPoint;
  if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
  if (terminateSimulation) *terminateSimulation = fmi3False;
  if (earlyReturn) *earlyReturn = fmi3False;
  if (lastSuccessfulTime) *lastSuccessfulTime = m->s.time;
  REQUIRE(m->s.phase == BC_RUNNING, "fmi3DoStep");
  int r = bc_do_step(&m->s, currentCommunicationPoint, communicationStepSize, m->msg);
  if (lastSuccessfulTime) *lastSuccessfulTime = m->s.time;
  /* Discard: the FMU is still at the step's start (lastSuccessfulTime) and may go on */
  if (r == BC_DISCARD) return fail(m, fmi3Discard, "fmi3DoStep");
  if (r) return fail(m, fmi3Error, "fmi3DoStep");
  return fmi3OK;
}
