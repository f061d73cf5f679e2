/* FMI 3.0 co-simulation interface of a cosim plant, on top of cosim_fmu.h.
 *
 * Supported: Float64, Int32 and Boolean scalars, FMU state get/set/serialise, early return from
 * fmi3DoStep at model events (when the importer allows it) and event mode. Everything else of the
 * API is present and answers with a logged error. */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "cosim_fmu.h"

#define M ((ModelInstance *)instance)
#define ANY_PHASE (PH_MASK(PH_INSTANTIATED) | PH_MASK(PH_INITIALIZATION) | PH_MASK(PH_STEP) | PH_MASK(PH_EVENT) | \
                   PH_MASK(PH_TERMINATED))

static fmi3Status result(ModelInstance *m, Status status) {
    if (status >= ST_ERROR) {
        m->phase = PH_ERROR;
    }
    return (fmi3Status)status;
}

static void sink(ModelInstance *m, Status status, const char *category, const char *message) {
    fmi3LogMessageCallback log = (fmi3LogMessageCallback)m->log_fn;
    if (log != NULL) {
        log(m->env, (fmi3Status)status, category, message);
    }
}

static fmi3Status unsupported(fmi3Instance instance, const char *fn) {
    if (instance != NULL) {
        cf_log(M, ST_ERROR, "logStatusError", "%s is not supported by this FMU", fn);
    }
    return fmi3Error;
}

/* For variable types the models do not have: fine for zero variables, an error otherwise. */
static fmi3Status no_vars(fmi3Instance instance, size_t nvr, const char *fn) {
    if (instance == NULL) {
        return fmi3Error;
    }
    if (nvr == 0) {
        return fmi3OK;
    }
    cf_log(M, ST_ERROR, "logStatusError", "%s: the model has no variables of this type", fn);
    return fmi3Error;
}

static int scalars(fmi3Instance instance, size_t nvr, size_t nValues, const char *fn) {
    if (nvr != nValues) {
        cf_log(M, ST_ERROR, "logStatusError", "%s: %lu values for %lu value references (the model has scalars only)",
               fn, (unsigned long)nValues, (unsigned long)nvr);
        return 0;
    }
    return 1;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)nCategories;
    (void)categories;
    if (instance == NULL) {
        return fmi3Error;
    }
    M->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    if (logMessage != NULL) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   instanceName != NULL ? "model exchange is not supported: use co-simulation"
                                        : "model exchange is not supported");
    }
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    ModelInstance *m;
    (void)resourcePath;
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    m = cf_new(instanceName);
    if (m == NULL) {
        if (logMessage != NULL) {
            logMessage(instanceEnvironment, fmi3Error, "logStatusError", "out of memory");
        }
        return NULL;
    }
    m->env = instanceEnvironment;
    m->log_fn = (void (*)(void))logMessage;
    m->log_sink = sink;
    m->logging_on = loggingOn ? 1 : 0;
    m->event_mode_used = eventModeUsed ? 1 : 0;
    m->early_return_allowed = earlyReturnAllowed ? 1 : 0;
    if (instantiationToken == NULL || strcmp(instantiationToken, INSTANTIATION_TOKEN) != 0) {
        cf_log(m, ST_ERROR, "logStatusError", "instantiation token %s does not match this binary's %s",
               instantiationToken != NULL ? instantiationToken : "(null)", INSTANTIATION_TOKEN);
        cf_free(m);
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        cf_log(m, ST_ERROR, "logStatusError", "intermediate variable access is not supported");
        cf_free(m);
        return NULL;
    }
    return m;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage != NULL) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError", "scheduled execution is not supported");
    }
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { cf_free(M); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (instance == NULL || !cf_phase_allows(M, "fmi3EnterInitializationMode", PH_MASK(PH_INSTANTIATED))) {
        return fmi3Error;
    }
    M->start_time = startTime;
    M->time = startTime;
    M->phase = PH_INITIALIZATION;
    M->outputs_stale = 1;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Status status;
    if (instance == NULL || !cf_phase_allows(M, "fmi3ExitInitializationMode", PH_MASK(PH_INITIALIZATION))) {
        return fmi3Error;
    }
    status = cf_exit_init(M);
    if (status <= ST_WARNING) {
        M->phase = M->event_mode_used ? PH_EVENT : PH_STEP;
    }
    return result(M, status);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    if (instance == NULL || !cf_phase_allows(M, "fmi3EnterEventMode", PH_MASK(PH_STEP))) {
        return fmi3Error;
    }
    M->phase = PH_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    if (instance == NULL || !cf_phase_allows(M, "fmi3Terminate", PH_MASK(PH_STEP) | PH_MASK(PH_EVENT))) {
        return fmi3Error;
    }
    M->phase = PH_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    if (instance == NULL) {
        return fmi3Error;
    }
    cf_defaults(M);
    return fmi3OK;
}

/* -- variables ---------------------------------------------------------------------------------- */
fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3GetFloat64")) {
        return fmi3Error;
    }
    return result(M, cf_get(M, VT_FLOAT64, vr, nvr, values, "fmi3GetFloat64"));
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3SetFloat64")) {
        return fmi3Error;
    }
    return result(M, cf_set(M, VT_FLOAT64, vr, nvr, values, "fmi3SetFloat64"));
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues) {
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3GetInt32")) {
        return fmi3Error;
    }
    return result(M, cf_get(M, VT_INT32, vr, nvr, values, "fmi3GetInt32"));
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[],
                        size_t nValues) {
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3SetInt32")) {
        return fmi3Error;
    }
    return result(M, cf_set(M, VT_INT32, vr, nvr, values, "fmi3SetInt32"));
}

/* fmi3Boolean is a C bool; the model stores Booleans as int: convert one at a time. */
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nValues) {
    size_t i;
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3GetBoolean")) {
        return fmi3Error;
    }
    for (i = 0; i < nvr; i++) {
        int value = 0;
        Status status = cf_get(M, VT_BOOL, &vr[i], 1, &value, "fmi3GetBoolean");
        if (status > ST_WARNING) {
            return result(M, status);
        }
        values[i] = value ? true : false;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    size_t i;
    if (instance == NULL || !scalars(instance, nvr, nValues, "fmi3SetBoolean")) {
        return fmi3Error;
    }
    for (i = 0; i < nvr; i++) {
        int value = values[i] ? 1 : 0;
        Status status = cf_set(M, VT_BOOL, &vr[i], 1, &value, "fmi3SetBoolean");
        if (status > ST_WARNING) {
            return result(M, status);
        }
    }
    return fmi3OK;
}

#define NO_GETTER(NAME, T)                                                                                        \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T values[],      \
                             size_t nValues) {                                                                  \
        (void)vr;                                                                                               \
        (void)values;                                                                                           \
        (void)nValues;                                                                                          \
        return no_vars(instance, nvr, "fmi3Get" #NAME);                                                         \
    }
#define NO_SETTER(NAME, T)                                                                                        \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const T values[], \
                             size_t nValues) {                                                                  \
        (void)vr;                                                                                               \
        (void)values;                                                                                           \
        (void)nValues;                                                                                          \
        return no_vars(instance, nvr, "fmi3Set" #NAME);                                                         \
    }

NO_GETTER(Float32, fmi3Float32)
NO_GETTER(Int8, fmi3Int8)
NO_GETTER(UInt8, fmi3UInt8)
NO_GETTER(Int16, fmi3Int16)
NO_GETTER(UInt16, fmi3UInt16)
NO_GETTER(UInt32, fmi3UInt32)
NO_GETTER(Int64, fmi3Int64)
NO_GETTER(UInt64, fmi3UInt64)
NO_GETTER(String, fmi3String)
NO_SETTER(Float32, fmi3Float32)
NO_SETTER(Int8, fmi3Int8)
NO_SETTER(UInt8, fmi3UInt8)
NO_SETTER(Int16, fmi3Int16)
NO_SETTER(UInt16, fmi3UInt16)
NO_SETTER(UInt32, fmi3UInt32)
NO_SETTER(Int64, fmi3Int64)
NO_SETTER(UInt64, fmi3UInt64)
NO_SETTER(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues) {
    (void)vr;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_vars(instance, nvr, "fmi3GetBinary");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    (void)vr;
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return no_vars(instance, nvr, "fmi3SetBinary");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    (void)vr;
    (void)values;
    return no_vars(instance, nvr, "fmi3GetClock");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    (void)vr;
    (void)values;
    return no_vars(instance, nvr, "fmi3SetClock");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference;
    (void)nDependencies;
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return unsupported(instance, "fmi3GetVariableDependencies");
}

/* -- FMU state ---------------------------------------------------------------------------------- */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ModelSnapshot *snap;
    if (instance == NULL || FMUState == NULL || !cf_phase_allows(M, "fmi3GetFMUState", ANY_PHASE)) {
        return fmi3Error;
    }
    snap = (ModelSnapshot *)(*FMUState != NULL ? *FMUState : malloc(sizeof(ModelSnapshot)));
    if (snap == NULL) {
        cf_log(M, ST_ERROR, "logStatusError", "fmi3GetFMUState: out of memory");
        return fmi3Error;
    }
    snap->phase = M->phase;
    snap->time = M->time;
    snap->v = M->v;
    snap->s = M->s;
    *FMUState = snap;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    const ModelSnapshot *snap = (const ModelSnapshot *)FMUState;
    if (instance == NULL || snap == NULL || !cf_phase_allows(M, "fmi3SetFMUState", ANY_PHASE)) {
        return fmi3Error;
    }
    M->phase = snap->phase;
    M->time = snap->time;
    M->v = snap->v;
    M->s = snap->s;
    M->outputs_stale = 1;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    if (instance == NULL || FMUState == NULL) {
        return fmi3Error;
    }
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState;
    if (instance == NULL || size == NULL) {
        return fmi3Error;
    }
    *size = sizeof(ModelSnapshot);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    if (instance == NULL || FMUState == NULL || size < sizeof(ModelSnapshot)) {
        return unsupported(instance, "fmi3SerializeFMUState with a buffer smaller than fmi3SerializedFMUStateSize");
    }
    memcpy(serializedState, FMUState, sizeof(ModelSnapshot));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    if (instance == NULL || FMUState == NULL || size != sizeof(ModelSnapshot)) {
        return unsupported(instance, "fmi3DeserializeFMUState of data of another size");
    }
    if (*FMUState == NULL) {
        *FMUState = malloc(sizeof(ModelSnapshot));
    }
    if (*FMUState == NULL) {
        return fmi3Error;
    }
    memcpy(*FMUState, serializedState, sizeof(ModelSnapshot));
    return fmi3OK;
}

/* -- derivatives, clocks, model exchange: not offered ----------------------------------------- */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterConfigurationMode");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3ExitConfigurationMode");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    (void)vr;
    (void)intervals;
    (void)qualifiers;
    return no_vars(instance, nvr, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return no_vars(instance, nvr, "fmi3GetIntervalFraction");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[]) {
    (void)vr;
    (void)shifts;
    return no_vars(instance, nvr, "fmi3GetShiftDecimal");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    return no_vars(instance, nvr, "fmi3GetShiftFraction");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    (void)vr;
    (void)intervals;
    return no_vars(instance, nvr, "fmi3SetIntervalDecimal");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    return no_vars(instance, nvr, "fmi3SetIntervalFraction");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
    (void)vr;
    (void)shifts;
    return no_vars(instance, nvr, "fmi3SetShiftDecimal");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)vr;
    (void)counters;
    (void)resolutions;
    return no_vars(instance, nvr, "fmi3SetShiftFraction");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return unsupported(instance, "fmi3EvaluateDiscreteStates");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    int again = 0;
    Status status;
    if (instance == NULL || !cf_phase_allows(M, "fmi3UpdateDiscreteStates", PH_MASK(PH_EVENT))) {
        return fmi3Error;
    }
    status = model_event_update(M, &again);
    model_outputs(M);
    M->outputs_stale = 0;
    if (discreteStatesNeedUpdate != NULL) {
        *discreteStatesNeedUpdate = again ? true : false;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = false;
    }
    if (nominalsOfContinuousStatesChanged != NULL) {
        *nominalsOfContinuousStatesChanged = false;
    }
    if (valuesOfContinuousStatesChanged != NULL) {
        *valuesOfContinuousStatesChanged = false;
    }
    if (nextEventTimeDefined != NULL) {
        *nextEventTimeDefined = false;
    }
    if (nextEventTime != NULL) {
        *nextEventTime = 0.0;
    }
    return result(M, status);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterContinuousTimeMode");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(instance, "fmi3CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return unsupported(instance, "fmi3SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    if (instance == NULL) {
        return fmi3Error;
    }
    return result(M, cf_event_indicators(M, eventIndicators, nEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    (void)nominals;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (instance == NULL || nEventIndicators == NULL) {
        return fmi3Error;
    }
    *nEventIndicators = N_EVENT_INDICATORS;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (instance == NULL || nContinuousStates == NULL) {
        return fmi3Error;
    }
    *nContinuousStates = 0; /* co-simulation only: the states are internal to the model */
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    if (instance == NULL || !cf_phase_allows(M, "fmi3EnterStepMode", PH_MASK(PH_EVENT))) {
        return fmi3Error;
    }
    M->phase = PH_STEP;
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    (void)vr;
    (void)nvr;
    (void)orders;
    (void)values;
    (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
    double reached = 0.0;
    int event = 0;
    Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (instance == NULL) {
        return fmi3Error;
    }
    status = cf_do_step(M, currentCommunicationPoint, communicationStepSize, &reached, &event);
    if (eventHandlingNeeded != NULL) {
        *eventHandlingNeeded = (event && M->event_mode_used) ? true : false;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = false;
    }
    if (earlyReturn != NULL) {
        *earlyReturn = (reached < currentCommunicationPoint + communicationStepSize) ? true : false;
    }
    if (lastSuccessfulTime != NULL) {
        *lastSuccessfulTime = reached;
    }
    return result(M, status);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference;
    (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition");
}
