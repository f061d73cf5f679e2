/* FMI 3.0 co-simulation interface of an exported machine (on top of machine.h).
 *
 * Offered: Float64, Int32 and Boolean scalars; early return from fmi3DoStep at the instant an
 * event-bearing output changes (when the importer allows it), and event mode (when the importer
 * uses it): at an event the outputs first hold their values just before it, after
 * fmi3UpdateDiscreteStates the values after it. Everything else of the API is present and
 * answers with a logged error. */
#include <string.h>

#include "fmi3Functions.h"
#include "machine.h"

#define M ((Machine *)instance)
#define ALL (PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP | PH_EVENT | PH_TERMINATED | PH_ERROR)
#define SETTABLE (PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP | PH_EVENT)
#define ENTER(fn, allowed)                                                                                            \
    do {                                                                                                              \
        if (!machine_enter(M, #fn, allowed)) {                                                                        \
            return fmi3Error;                                                                                         \
        }                                                                                                             \
    } while (0)

static void sink(const Machine *m, MStatus status, const char *category, const char *message) {
    fmi3LogMessageCallback log;
    *(void **)(&log) = *(void *const *)(&m->log_fn);
    if (log != NULL) {
        log(m->env, (fmi3Status)status, category, message);
    }
}

static fmi3Status unsupported(fmi3Instance instance, const char *fn) {
    return (fmi3Status)machine_unsupported(M, fn);
}

/* One value per value reference: the machine's variables are scalars. */
static int scalars(fmi3Instance instance, const char *fn, size_t nvr, size_t nValues) {
    if (nvr != nValues) {
        machine_log(M, MS_ERROR, "logStatusError", "%s: %lu values for %lu value references (scalars only)", fn,
                    (unsigned long)nValues, (unsigned long)nvr);
        machine_result(M, MS_ERROR);
        return 0;
    }
    return 1;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)nCategories;
    (void)categories;
    ENTER(fmi3SetDebugLogging, ALL);
    M->logging_on = loggingOn ? 1 : 0;
    return (fmi3Status)machine_call(M, "set_debug_logging", "(i)", M->logging_on);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    if (logMessage != NULL) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "model exchange is not supported: a machine is a co-simulation FMU");
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
    void (*log_fn)(void);
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (nRequiredIntermediateVariables > 0) {
        if (logMessage != NULL) {
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "intermediate variable access is not supported");
        }
        return NULL;
    }
    *(void **)(&log_fn) = *(void **)(&logMessage);
    return machine_new(3, instanceName, instantiationToken, resourcePath, sink, instanceEnvironment, NULL, log_fn,
                       loggingOn ? 1 : 0, eventModeUsed ? 1 : 0, earlyReturnAllowed ? 1 : 0);
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

void fmi3FreeInstance(fmi3Instance instance) { machine_free(M); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    fmi3Status status;
    (void)toleranceDefined;
    (void)tolerance;
    ENTER(fmi3EnterInitializationMode, PH_INSTANTIATED);
    status = (fmi3Status)machine_call(M, "enter_initialization", "(did)", startTime, stopTimeDefined ? 1 : 0,
                                      stopTime);
    if (status <= fmi3Warning) {
        M->phase = PH_INITIALIZATION;
    }
    return status;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    fmi3Status status;
    ENTER(fmi3ExitInitializationMode, PH_INITIALIZATION);
    status = (fmi3Status)machine_call(M, "exit_initialization", "()");
    if (status <= fmi3Warning) {
        M->phase = M->event_mode_used ? PH_EVENT : PH_STEP; /* FMI 3.0: event mode first if used */
    }
    return status;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER(fmi3EnterEventMode, PH_STEP);
    M->phase = PH_EVENT;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    fmi3Status status;
    ENTER(fmi3Terminate, PH_STEP | PH_EVENT);
    status = (fmi3Status)machine_call(M, "terminate", "()");
    if (status <= fmi3Warning) {
        M->phase = PH_TERMINATED;
    }
    return status;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    fmi3Status status;
    ENTER(fmi3Reset, ALL);
    status = (fmi3Status)machine_call(M, "reset", "()");
    if (status <= fmi3Warning) {
        M->phase = PH_INSTANTIATED;
    }
    return status;
}

/* -- variables ---------------------------------------------------------------------------------- */
#define GETTER(NAME, CTYPE, KIND)                                                                                     \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, CTYPE values[],       \
                             size_t nValues) {                                                                        \
        ENTER(fmi3Get##NAME, ALL);                                                                                   \
        if (!scalars(instance, "fmi3Get" #NAME, nvr, nValues)) {                                                     \
            return fmi3Error;                                                                                         \
        }                                                                                                             \
        return (fmi3Status)machine_get(M, "fmi3Get" #NAME, KIND, vr, nvr, values);                                   \
    }
#define SETTER(NAME, CTYPE, KIND)                                                                                     \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const CTYPE values[], \
                             size_t nValues) {                                                                        \
        ENTER(fmi3Set##NAME, SETTABLE);                                                                              \
        if (!scalars(instance, "fmi3Set" #NAME, nvr, nValues)) {                                                     \
            return fmi3Error;                                                                                         \
        }                                                                                                             \
        return (fmi3Status)machine_set(M, "fmi3Set" #NAME, KIND, vr, nvr, values);                                   \
    }

GETTER(Float64, fmi3Float64, VK_FLOAT64)
GETTER(Int32, fmi3Int32, VK_INT32)
GETTER(Boolean, fmi3Boolean, VK_BOOLEAN)
SETTER(Float64, fmi3Float64, VK_FLOAT64)
SETTER(Int32, fmi3Int32, VK_INT32)
SETTER(Boolean, fmi3Boolean, VK_BOOLEAN)

/* The types no exported machine has: fine for no value references, an error otherwise. */
static fmi3Status no_vars(fmi3Instance instance, const char *fn, size_t nvr) {
    if (!machine_enter(M, fn, ALL)) {
        return fmi3Error;
    }
    if (nvr == 0) {
        return fmi3OK;
    }
    machine_log(M, MS_ERROR, "logStatusError", "%s: the machine has no variable of this type", fn);
    return (fmi3Status)machine_result(M, MS_ERROR);
}

#define NO_VARIABLES_1(NAME, T1)                                                                                      \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a) {                  \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        return no_vars(instance, "fmi3" #NAME, nvr);                                                                 \
    }
#define NO_VARIABLES_2(NAME, T1, T2)                                                                                  \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a, T2 b) {            \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        (void)b;                                                                                                     \
        return no_vars(instance, "fmi3" #NAME, nvr);                                                                 \
    }
#define NO_VARIABLES_3(NAME, T1, T2, T3)                                                                              \
    fmi3Status fmi3##NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, T1 a, T2 b, T3 c) {      \
        (void)vr;                                                                                                    \
        (void)a;                                                                                                     \
        (void)b;                                                                                                     \
        (void)c;                                                                                                     \
        return no_vars(instance, "fmi3" #NAME, nvr);                                                                 \
    }

NO_VARIABLES_2(GetFloat32, fmi3Float32 *, size_t)
NO_VARIABLES_2(GetInt8, fmi3Int8 *, size_t)
NO_VARIABLES_2(GetUInt8, fmi3UInt8 *, size_t)
NO_VARIABLES_2(GetInt16, fmi3Int16 *, size_t)
NO_VARIABLES_2(GetUInt16, fmi3UInt16 *, size_t)
NO_VARIABLES_2(GetUInt32, fmi3UInt32 *, size_t)
NO_VARIABLES_2(GetInt64, fmi3Int64 *, size_t)
NO_VARIABLES_2(GetUInt64, fmi3UInt64 *, size_t)
NO_VARIABLES_2(GetString, fmi3String *, size_t)
NO_VARIABLES_3(GetBinary, size_t *, fmi3Binary *, size_t)
NO_VARIABLES_2(SetFloat32, const fmi3Float32 *, size_t)
NO_VARIABLES_2(SetInt8, const fmi3Int8 *, size_t)
NO_VARIABLES_2(SetUInt8, const fmi3UInt8 *, size_t)
NO_VARIABLES_2(SetInt16, const fmi3Int16 *, size_t)
NO_VARIABLES_2(SetUInt16, const fmi3UInt16 *, size_t)
NO_VARIABLES_2(SetUInt32, const fmi3UInt32 *, size_t)
NO_VARIABLES_2(SetInt64, const fmi3Int64 *, size_t)
NO_VARIABLES_2(SetUInt64, const fmi3UInt64 *, size_t)
NO_VARIABLES_2(SetString, const fmi3String *, size_t)
NO_VARIABLES_3(SetBinary, const size_t *, const fmi3Binary *, size_t)
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

/* -- FMU state: a SimPy simulation cannot be copied (its processes are running generators) ------ */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    (void)FMUState;
    return unsupported(instance, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    (void)FMUState;
    return unsupported(instance, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    (void)FMUState;
    return unsupported(instance, "fmi3FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState;
    (void)size;
    return unsupported(instance, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    (void)FMUState;
    (void)serializedState;
    (void)size;
    return unsupported(instance, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    (void)serializedState;
    (void)size;
    (void)FMUState;
    return unsupported(instance, "fmi3DeserializeFMUState");
}

/* -- derivatives, configuration, model exchange: not offered ------------------------------------ */
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

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return unsupported(instance, "fmi3EvaluateDiscreteStates");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    fmi3Status status;
    ENTER(fmi3UpdateDiscreteStates, PH_EVENT);
    status = (fmi3Status)machine_call(M, "update_discrete_states", "()");
    if (discreteStatesNeedUpdate != NULL) {
        *discreteStatesNeedUpdate = false;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = M->step[SR_TERMINATE] != 0.0;
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
    return status;
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
    (void)eventIndicators;
    (void)nEventIndicators;
    return unsupported(instance, "fmi3GetEventIndicators");
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
    ENTER(fmi3GetNumberOfEventIndicators, ALL);
    if (nEventIndicators != NULL) {
        *nEventIndicators = 0;
    }
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    ENTER(fmi3GetNumberOfContinuousStates, ALL);
    if (nContinuousStates != NULL) {
        *nContinuousStates = 0;
    }
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    ENTER(fmi3EnterStepMode, PH_EVENT);
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
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER(fmi3DoStep, PH_STEP);
    status = (fmi3Status)machine_call(M, "do_step", "(dd)", currentCommunicationPoint, communicationStepSize);
    if (eventHandlingNeeded != NULL) {
        *eventHandlingNeeded = M->step[SR_EVENT] != 0.0;
    }
    if (terminateSimulation != NULL) {
        *terminateSimulation = M->step[SR_TERMINATE] != 0.0;
    }
    if (earlyReturn != NULL) {
        *earlyReturn = M->step[SR_EARLY] != 0.0;
    }
    if (lastSuccessfulTime != NULL) {
        *lastSuccessfulTime = M->step[SR_LAST_TIME];
    }
    return status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference;
    (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition");
}
