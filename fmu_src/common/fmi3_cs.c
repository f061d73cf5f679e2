/* FMI 3.0 co-simulation interface of a cosim plant, on top of cosim_fmu.h.
 *
 * Supported: every variable type (Float32/64, Int8..UInt64, Boolean, String, Binary, Enumeration),
 * scalars and arrays, FMU state get/set/serialise, early return from fmi3DoStep at model events (when
 * the importer allows it), event mode, and terminate requests of the model. Everything else of the
 * API (clocks, derivatives, configuration mode) is present and answers with a logged error. */
#include <string.h>

#include "fmi3Functions.h"
#include "cosim_fmu.h"

#define M ((ModelInstance *)instance)
/* The entry check: return fmi3Error unless the state table allows the call. */
#define ENTER(fn)                                                                                             \
    do {                                                                                                      \
        if (!cf_enter(M, CALL_##fn)) {                                                                        \
            return fmi3Error;                                                                                 \
        }                                                                                                     \
    } while (0)

static fmi3Status result(ModelInstance *m, Status status) { return (fmi3Status)cf_result(m, status); }

static void sink(ModelInstance *m, Status status, const char *category, const char *message) {
    fmi3LogMessageCallback log = (fmi3LogMessageCallback)m->log_fn;
    if (log != NULL) {
        log(m->env, (fmi3Status)status, category, message);
    }
}

/* The entry check, then an error: for the functions these FMUs do not offer. */
static fmi3Status unsupported(fmi3Instance instance, FmiCall call) {
    if (!cf_enter(M, call)) {
        return fmi3Error;
    }
    return result(M, cf_unsupported(M, call));
}

/* The entry check, then fine for no value references: for variables no model has. */
static fmi3Status no_vars(fmi3Instance instance, FmiCall call, size_t nvr) {
    if (!cf_enter(M, call)) {
        return fmi3Error;
    }
    return result(M, cf_no_vars(M, call, nvr));
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)nCategories;
    (void)categories;
    ENTER(fmi3SetDebugLogging);
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

void fmi3FreeInstance(fmi3Instance instance) {
    if (cf_enter(M, CALL_fmi3FreeInstance)) {
        cf_free(M);
    }
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ENTER(fmi3EnterInitializationMode);
    M->start_time = startTime;
    M->time = startTime;
    M->phase = PH_INITIALIZATION;
    M->outputs_stale = 1;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Status status;
    ENTER(fmi3ExitInitializationMode);
    status = cf_exit_init(M);
    if (status <= ST_WARNING) {
        M->phase = M->event_mode_used ? PH_EVENT : PH_STEP;
    }
    return result(M, status);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER(fmi3EnterEventMode);
    M->phase = PH_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ENTER(fmi3Terminate);
    M->phase = PH_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    ENTER(fmi3Reset);
    cf_defaults(M);
    return fmi3OK;
}

/* -- variables ---------------------------------------------------------------------------------- */
/* One getter and one setter per type: the shared helpers find each variable, check nValues (the sum of
 * the variables' element counts: arrays are passed flat, row-major) and convert where the storage
 * differs (Booleans are int inside, fmi3Boolean outside; an Enumeration is an Int64). */
#define ACCESSORS(NAME, CTYPE, VT)                                                                                 \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, CTYPE values[],   \
                             size_t nValues) {                                                                   \
        ENTER(fmi3Get##NAME);                                                                                    \
        return result(M, cf_get(M, CALL_fmi3Get##NAME, VT, vr, nvr, (void *)values, nValues));                 \
    }                                                                                                            \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,                   \
                             const CTYPE values[], size_t nValues) {                                             \
        ENTER(fmi3Set##NAME);                                                                                    \
        return result(M, cf_set(M, CALL_fmi3Set##NAME, VT, vr, nvr, (const void *)values, nValues));           \
    }

ACCESSORS(Float32, fmi3Float32, VT_FLOAT32)
ACCESSORS(Float64, fmi3Float64, VT_FLOAT64)
ACCESSORS(Int8, fmi3Int8, VT_INT8)
ACCESSORS(UInt8, fmi3UInt8, VT_UINT8)
ACCESSORS(Int16, fmi3Int16, VT_INT16)
ACCESSORS(UInt16, fmi3UInt16, VT_UINT16)
ACCESSORS(Int32, fmi3Int32, VT_INT32)
ACCESSORS(UInt32, fmi3UInt32, VT_UINT32)
ACCESSORS(Int64, fmi3Int64, VT_INT64)
ACCESSORS(UInt64, fmi3UInt64, VT_UINT64)
ACCESSORS(Boolean, fmi3Boolean, VT_BOOL_C)
ACCESSORS(String, fmi3String, VT_STRING)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues) {
    ENTER(fmi3GetBinary);
    return result(M, cf_get_binary(M, CALL_fmi3GetBinary, vr, nvr, valueSizes, (const unsigned char **)values,
                                   nValues));
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    ENTER(fmi3SetBinary);
    return result(M, cf_set_binary(M, CALL_fmi3SetBinary, vr, nvr, valueSizes, (const unsigned char *const *)values,
                                   nValues));
}

/* The functions for variables no model has (clocks and their intervals and shifts): fine for no
 * value references, an error otherwise. NO_VARIABLES_n defines one with n arguments after the value
 * references. */
#define NO_VARIABLES_1(NAME, T1)                                                                                     \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a) {                  \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        return no_vars(instance, CALL_fmi3##NAME, nvr);                                                              \
    }
#define NO_VARIABLES_2(NAME, T1, T2)                                                                                 \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a, T2 b) {            \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        (void)b;                                                                                                     \
        return no_vars(instance, CALL_fmi3##NAME, nvr);                                                              \
    }
#define NO_VARIABLES_3(NAME, T1, T2, T3)                                                                             \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a, T2 b, T3 c) {      \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        (void)b;                                                                                                     \
        (void)c;                                                                                                     \
        return no_vars(instance, CALL_fmi3##NAME, nvr);                                                              \
    }

NO_VARIABLES_1(GetClock, fmi3Clock *)
NO_VARIABLES_1(SetClock, const fmi3Clock *)
NO_VARIABLES_2(GetIntervalDecimal, fmi3Float64 *, fmi3IntervalQualifier *)
NO_VARIABLES_3(GetIntervalFraction, fmi3UInt64 *, fmi3UInt64 *, fmi3IntervalQualifier *)
NO_VARIABLES_1(GetShiftDecimal, fmi3Float64 *)
NO_VARIABLES_2(GetShiftFraction, fmi3UInt64 *, fmi3UInt64 *)
NO_VARIABLES_1(SetIntervalDecimal, const fmi3Float64 *)
NO_VARIABLES_2(SetIntervalFraction, const fmi3UInt64 *, const fmi3UInt64 *)
NO_VARIABLES_1(SetShiftDecimal, const fmi3Float64 *)
NO_VARIABLES_2(SetShiftFraction, const fmi3UInt64 *, const fmi3UInt64 *)

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference;
    (void)nDependencies;
    return unsupported(instance, CALL_fmi3GetNumberOfVariableDependencies);
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
    return unsupported(instance, CALL_fmi3GetVariableDependencies);
}

/* -- FMU state ---------------------------------------------------------------------------------- */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER(fmi3GetFMUState);
    return result(M, cf_state_get(M, CALL_fmi3GetFMUState, FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    ENTER(fmi3SetFMUState);
    return result(M, cf_state_set(M, CALL_fmi3SetFMUState, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER(fmi3FreeFMUState);
    return result(M, cf_state_free(M, CALL_fmi3FreeFMUState, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState;
    ENTER(fmi3SerializedFMUStateSize);
    return result(M, cf_state_size(M, CALL_fmi3SerializedFMUStateSize, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    ENTER(fmi3SerializeFMUState);
    return result(M, cf_state_serialize(M, CALL_fmi3SerializeFMUState, FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    ENTER(fmi3DeserializeFMUState);
    return result(M, cf_state_deserialize(M, CALL_fmi3DeserializeFMUState, serializedState, size, FMUState));
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
    return unsupported(instance, CALL_fmi3GetDirectionalDerivative);
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
    return unsupported(instance, CALL_fmi3GetAdjointDerivative);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, CALL_fmi3EnterConfigurationMode);
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, CALL_fmi3ExitConfigurationMode);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return unsupported(instance, CALL_fmi3EvaluateDiscreteStates);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    int again = 0;
    Status status;
    ENTER(fmi3UpdateDiscreteStates);
    status = model_event_update(M, &again);
    model_outputs(M);
    M->outputs_stale = 0;
    if (discreteStatesNeedUpdate != NULL) {
        *discreteStatesNeedUpdate = again ? true : false;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = M->terminate_requested ? true : false;
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
    return unsupported(instance, CALL_fmi3EnterContinuousTimeMode);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(instance, CALL_fmi3CompletedIntegratorStep);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return unsupported(instance, CALL_fmi3SetTime);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, CALL_fmi3SetContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives;
    (void)nContinuousStates;
    return unsupported(instance, CALL_fmi3GetContinuousStateDerivatives);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    ENTER(fmi3GetEventIndicators);
    return result(M, cf_event_indicators(M, CALL_fmi3GetEventIndicators, eventIndicators, nEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, CALL_fmi3GetContinuousStates);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    (void)nominals;
    (void)nContinuousStates;
    return unsupported(instance, CALL_fmi3GetNominalsOfContinuousStates);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    ENTER(fmi3GetNumberOfEventIndicators);
    if (nEventIndicators == NULL) {
        return result(M, cf_null_argument(M, CALL_fmi3GetNumberOfEventIndicators, "nEventIndicators"));
    }
    *nEventIndicators = N_EVENT_INDICATORS;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    ENTER(fmi3GetNumberOfContinuousStates);
    if (nContinuousStates == NULL) {
        return result(M, cf_null_argument(M, CALL_fmi3GetNumberOfContinuousStates, "nContinuousStates"));
    }
    *nContinuousStates = 0; /* co-simulation only: the states are internal to the model */
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER(fmi3EnterStepMode);
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
    return unsupported(instance, CALL_fmi3GetOutputDerivatives);
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
    double reached = 0.0;
    int event = 0;
    Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER(fmi3DoStep);
    status = cf_do_step(M, CALL_fmi3DoStep, currentCommunicationPoint, communicationStepSize, &reached, &event);
    if (eventHandlingNeeded != NULL) {
        *eventHandlingNeeded = (event && M->event_mode_used) ? true : false;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = M->terminate_requested ? true : false;
    }
    if (earlyReturn != NULL) { /* a terminate request ends the step early even without early return */
        *earlyReturn = (M->early_return_allowed && reached < currentCommunicationPoint + communicationStepSize)
                           ? true : false;
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
    return unsupported(instance, CALL_fmi3ActivateModelPartition);
}
