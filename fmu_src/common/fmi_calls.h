/* Which FMI calls each instance state allows: the co-simulation state machines of FMI 2.0 and
 * FMI 3.0 as one table, consulted by one entry check (cf_enter, fmi_calls.c) at the top of every
 * FMI function that takes an instance. (fmi2GetVersion, fmi2GetTypesPlatform, fmi3GetVersion and
 * the instantiate functions take none: they are allowed at any time.)
 *
 * One row per function, one column per state of ModelInstance.phase, 1 = allowed:
 *
 *   I instantiated   N initialization mode   S step mode (FMI 2.0: stepComplete)
 *   E event mode (FMI 3.0 only)   T terminated   R error   F fatal
 *
 * The states an instance of these FMUs never enters are left out: FMI 2.0 stepInProgress and
 * stepCanceled (doStep runs to its end and never returns fmi2Pending); FMI 3.0 Configuration,
 * Reconfiguration, Step Discarded, Intermediate Update and Clock Activation Mode (no structural
 * parameters, no fmi3Discard, no intermediate update, no scheduled execution). Functions allowed
 * only there have an empty row. A model that asks to end the simulation (terminate_requested in
 * cosim_fmu.h) stays in step or event mode: FMI 2.0 doStep then returns fmi2Discard (its stepFailed
 * state, whose calls - getters, status queries, Terminate, Reset, FreeInstance - the S column
 * allows) and FMI 3.0 reports terminateSimulation; a further doStep is refused by cf_do_step.
 *
 * A function that returns fmi2Error / fmi3Error leaves the instance in the error state (R), fmi2Fatal
 * / fmi3Fatal in the fatal state (F), where nothing is allowed. FMI 2.0 has an error state of its
 * own; FMI 3.0 moves an instance that returned fmi3Error to Terminated, so for the fmi3 rows the R
 * column repeats the T column (getters for debugging, FMU state, Reset, FreeInstance).
 *
 * FMI 3.0 fmi3Get{VariableType} in Instantiated gives the start values (the standard's Instantiated
 * state). fmi3GetEventIndicators, fmi3GetNumberOfEventIndicators and fmi3GetNumberOfContinuousStates
 * belong to Model Exchange; these FMUs offer them to co-simulation importers as an extension, in the
 * states of the Model Exchange table, Step Mode standing for Continuous-Time Mode. The clock rows
 * (no model has clocks) follow the standard's Initialization and Event Mode descriptions.
 *
 * To add a function: add its row here; the enum constant CALL_<name> and its name string follow. */
#ifndef COSIM_FMI_CALLS_H
#define COSIM_FMI_CALLS_H

#define FMI_CALLS(X)                                                     \
    /* FMI 2.0 co-simulation                 I  N  S  E  T  R  F */      \
    X(fmi2SetDebugLogging,                   1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2FreeInstance,                      1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SetupExperiment,                   1, 0, 0, 0, 0, 0, 0)        \
    X(fmi2EnterInitializationMode,           1, 0, 0, 0, 0, 0, 0)        \
    X(fmi2ExitInitializationMode,            0, 1, 0, 0, 0, 0, 0)        \
    X(fmi2Terminate,                         0, 0, 1, 0, 0, 0, 0)        \
    X(fmi2Reset,                             1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2GetReal,                           0, 1, 1, 0, 1, 1, 0)        \
    X(fmi2GetInteger,                        0, 1, 1, 0, 1, 1, 0)        \
    X(fmi2GetBoolean,                        0, 1, 1, 0, 1, 1, 0)        \
    X(fmi2GetString,                         0, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SetReal,                           1, 1, 1, 0, 0, 0, 0)        \
    X(fmi2SetInteger,                        1, 1, 1, 0, 0, 0, 0)        \
    X(fmi2SetBoolean,                        1, 1, 1, 0, 0, 0, 0)        \
    X(fmi2SetString,                         1, 1, 1, 0, 0, 0, 0)        \
    X(fmi2GetFMUstate,                       1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SetFMUstate,                       1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2FreeFMUstate,                      1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SerializedFMUstateSize,            1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SerializeFMUstate,                 1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2DeSerializeFMUstate,               1, 1, 1, 0, 1, 1, 0)        \
    X(fmi2GetDirectionalDerivative,          0, 1, 1, 0, 1, 1, 0)        \
    X(fmi2SetRealInputDerivatives,           1, 1, 1, 0, 0, 0, 0)        \
    X(fmi2GetRealOutputDerivatives,          0, 0, 1, 0, 1, 1, 0)        \
    X(fmi2DoStep,                            0, 0, 1, 0, 0, 0, 0)        \
    X(fmi2CancelStep,                        0, 0, 0, 0, 0, 0, 0)        \
    X(fmi2GetStatus,                         0, 0, 1, 0, 1, 0, 0)        \
    X(fmi2GetRealStatus,                     0, 0, 1, 0, 1, 0, 0)        \
    X(fmi2GetIntegerStatus,                  0, 0, 1, 0, 1, 0, 0)        \
    X(fmi2GetBooleanStatus,                  0, 0, 1, 0, 1, 0, 0)        \
    X(fmi2GetStringStatus,                   0, 0, 1, 0, 1, 0, 0)        \
    /* FMI 3.0 co-simulation                 I  N  S  E  T  R  F */      \
    X(fmi3SetDebugLogging,                   1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3FreeInstance,                      1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3EnterInitializationMode,           1, 0, 0, 0, 0, 0, 0)        \
    X(fmi3ExitInitializationMode,            0, 1, 0, 0, 0, 0, 0)        \
    X(fmi3EnterEventMode,                    0, 0, 1, 0, 0, 0, 0)        \
    X(fmi3Terminate,                         0, 0, 1, 1, 0, 0, 0)        \
    X(fmi3Reset,                             1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetFloat32,                        1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetFloat64,                        1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetInt8,                           1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetUInt8,                          1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetInt16,                          1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetUInt16,                         1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetInt32,                          1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetUInt32,                         1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetInt64,                          1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetUInt64,                         1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetBoolean,                        1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetString,                         1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetBinary,                         1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetClock,                          0, 0, 0, 1, 0, 0, 0)        \
    X(fmi3SetFloat32,                        1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetFloat64,                        1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetInt8,                           1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetUInt8,                          1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetInt16,                          1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetUInt16,                         1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetInt32,                          1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetUInt32,                         1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetInt64,                          1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetUInt64,                         1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetBoolean,                        1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetString,                         1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetBinary,                         1, 1, 1, 1, 0, 0, 0)        \
    X(fmi3SetClock,                          0, 0, 0, 1, 0, 0, 0)        \
    X(fmi3GetNumberOfVariableDependencies,   1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetVariableDependencies,           1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetFMUState,                       1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3SetFMUState,                       1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3FreeFMUState,                      1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3SerializedFMUStateSize,            1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3SerializeFMUState,                 1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3DeserializeFMUState,               1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetDirectionalDerivative,          0, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetAdjointDerivative,              0, 1, 1, 1, 1, 1, 0)        \
    X(fmi3EnterConfigurationMode,            1, 0, 1, 0, 0, 0, 0)        \
    X(fmi3ExitConfigurationMode,             0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3GetIntervalDecimal,                0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3GetIntervalFraction,               0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3GetShiftDecimal,                   0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3GetShiftFraction,                  0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3SetIntervalDecimal,                0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3SetIntervalFraction,               0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3SetShiftDecimal,                   0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3SetShiftFraction,                  0, 1, 0, 1, 0, 0, 0)        \
    X(fmi3EvaluateDiscreteStates,            0, 0, 0, 1, 0, 0, 0)        \
    X(fmi3UpdateDiscreteStates,              0, 0, 0, 1, 0, 0, 0)        \
    X(fmi3EnterContinuousTimeMode,           0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3CompletedIntegratorStep,           0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3SetTime,                           0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3SetContinuousStates,               0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3GetContinuousStateDerivatives,     0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3GetEventIndicators,                0, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetContinuousStates,               0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3GetNominalsOfContinuousStates,     0, 0, 0, 0, 0, 0, 0)        \
    X(fmi3GetNumberOfEventIndicators,        1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3GetNumberOfContinuousStates,       1, 1, 1, 1, 1, 1, 0)        \
    X(fmi3EnterStepMode,                     0, 0, 0, 1, 0, 0, 0)        \
    X(fmi3GetOutputDerivatives,              0, 0, 1, 0, 1, 1, 0)        \
    X(fmi3DoStep,                            0, 0, 1, 0, 0, 0, 0)        \
    X(fmi3ActivateModelPartition,            0, 0, 0, 0, 0, 0, 0)

typedef enum {
#define CALL_ENUM(name, i, n, s, e, t, r, f) CALL_##name,
    FMI_CALLS(CALL_ENUM)
#undef CALL_ENUM
    N_FMI_CALLS
} FmiCall;

struct ModelInstance;

/* The entry check. 1 if `call` is allowed in the instance's state. Otherwise 0: it logs
 * "<function> must not be called in <state>" and puts the instance in the error state (the
 * standards' answer to an illegal call); a NULL instance is refused without a message. */
int cf_enter(struct ModelInstance *m, FmiCall call);
/* The function's name, e.g. "fmi3DoStep", for messages. */
const char *cf_call_name(FmiCall call);

#endif
