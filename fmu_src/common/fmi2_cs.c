/* FMI 2.0 co-simulation interface of a cosim plant, on top of cosim_fmu.h. Every function that
 * takes an instance begins with the entry check ENTER (the state table: fmi_calls.h). */
#include <string.h>

#include "fmi2Functions.h"
#include "cosim_fmu.h"

#define M ((ModelInstance *)c)
/* The entry check: return fmi2Error unless the state table allows the call. */
#define ENTER(fn)                                                                                             \
    do {                                                                                                      \
        if (!cf_enter(M, CALL_##fn)) {                                                                        \
            return fmi2Error;                                                                                 \
        }                                                                                                     \
    } while (0)

static fmi2Status result(ModelInstance *m, Status status) { return (fmi2Status)cf_result(m, status); }

/* The FMI 2.0 logger takes a printf format. Importers written in other languages often cannot read
 * variadic arguments, so the message itself is the format, with any '%' doubled. */
static void sink(ModelInstance *m, Status status, const char *category, const char *message) {
    const fmi2CallbackFunctions *cb = (const fmi2CallbackFunctions *)m->callbacks;
    char format[2048];
    size_t i = 0;
    if (cb == NULL || cb->logger == NULL) {
        return;
    }
    for (; *message != '\0' && i + 2 < sizeof(format); message++) {
        if (*message == '%') {
            format[i++] = '%';
        }
        format[i++] = *message;
    }
    format[i] = '\0';
    cb->logger(cb->componentEnvironment, m->instance_name, (fmi2Status)status, category, format);
}

/* The entry check, then an error: for the functions these FMUs do not offer. */
static fmi2Status unsupported(fmi2Component c, FmiCall call) {
    if (!cf_enter(M, call)) {
        return fmi2Error;
    }
    return result(M, cf_unsupported(M, call));
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    ENTER(fmi2SetDebugLogging);
    M->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    ModelInstance *m;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->logger == NULL) {
        return NULL;
    }
    m = cf_new(instanceName);
    if (m == NULL) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                          "out of memory");
        return NULL;
    }
    m->callbacks = functions;
    m->log_sink = sink;
    m->logging_on = loggingOn ? 1 : 0;
    if (fmuType != fmi2CoSimulation) {
        cf_log(m, ST_ERROR, "logStatusError", "%s supports co-simulation only", MODEL_IDENTIFIER);
        cf_free(m);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, INSTANTIATION_TOKEN) != 0) {
        cf_log(m, ST_ERROR, "logStatusError", "GUID %s does not match this binary's %s",
               fmuGUID != NULL ? fmuGUID : "(null)", INSTANTIATION_TOKEN);
        cf_free(m);
        return NULL;
    }
    return m;
}

void fmi2FreeInstance(fmi2Component c) {
    if (cf_enter(M, CALL_fmi2FreeInstance)) {
        cf_free(M);
    }
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ENTER(fmi2SetupExperiment);
    M->start_time = startTime;
    M->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ENTER(fmi2EnterInitializationMode);
    M->phase = PH_INITIALIZATION;
    M->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Status status;
    ENTER(fmi2ExitInitializationMode);
    status = cf_exit_init(M);
    if (status <= ST_WARNING) {
        M->phase = PH_STEP;
    }
    return result(M, status);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ENTER(fmi2Terminate);
    M->phase = PH_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    ENTER(fmi2Reset);
    cf_defaults(M);
    return fmi2OK;
}

/* -- variables ---------------------------------------------------------------------------------- */
/* FMI 2.0 has scalars only: one value per value reference. An Enumeration is read and set as Integer. */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    ENTER(fmi2GetReal);
    return result(M, cf_get(M, CALL_fmi2GetReal, VT_FLOAT64, vr, nvr, value, nvr));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    ENTER(fmi2GetInteger);
    return result(M, cf_get(M, CALL_fmi2GetInteger, VT_INT32, vr, nvr, value, nvr));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    ENTER(fmi2GetBoolean);
    return result(M, cf_get(M, CALL_fmi2GetBoolean, VT_BOOL, vr, nvr, value, nvr));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    ENTER(fmi2GetString);
    return result(M, cf_get(M, CALL_fmi2GetString, VT_STRING, vr, nvr, (void *)value, nvr));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    ENTER(fmi2SetReal);
    return result(M, cf_set(M, CALL_fmi2SetReal, VT_FLOAT64, vr, nvr, value, nvr));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    ENTER(fmi2SetInteger);
    return result(M, cf_set(M, CALL_fmi2SetInteger, VT_INT32, vr, nvr, value, nvr));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    ENTER(fmi2SetBoolean);
    return result(M, cf_set(M, CALL_fmi2SetBoolean, VT_BOOL, vr, nvr, value, nvr));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    ENTER(fmi2SetString);
    return result(M, cf_set(M, CALL_fmi2SetString, VT_STRING, vr, nvr, value, nvr));
}

/* -- FMU state ---------------------------------------------------------------------------------- */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER(fmi2GetFMUstate);
    return result(M, cf_state_get(M, CALL_fmi2GetFMUstate, state));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    ENTER(fmi2SetFMUstate);
    return result(M, cf_state_set(M, CALL_fmi2SetFMUstate, state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ENTER(fmi2FreeFMUstate);
    return result(M, cf_state_free(M, CALL_fmi2FreeFMUstate, state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state;
    ENTER(fmi2SerializedFMUstateSize);
    return result(M, cf_state_size(M, CALL_fmi2SerializedFMUstateSize, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    ENTER(fmi2SerializeFMUstate);
    return result(M, cf_state_serialize(M, CALL_fmi2SerializeFMUstate, state, (unsigned char *)bytes, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    ENTER(fmi2DeSerializeFMUstate);
    return result(M, cf_state_deserialize(M, CALL_fmi2DeSerializeFMUstate, (const unsigned char *)bytes, size,
                                          state));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, CALL_fmi2GetDirectionalDerivative);
}

/* -- co-simulation ----------------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, CALL_fmi2SetRealInputDerivatives);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, CALL_fmi2GetRealOutputDerivatives);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    double reached;
    int event;
    Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER(fmi2DoStep);
    /* FMI 2.0 has no early return: events inside the step are handled by the model itself. */
    M->early_return_allowed = 0;
    status = cf_do_step(M, CALL_fmi2DoStep, currentCommunicationPoint, communicationStepSize, &reached, &event);
    if (status <= ST_WARNING && M->terminate_requested) {
        /* the model asked to end the simulation at M->time: fmi2Discard, then fmi2Terminated = true and
         * fmi2LastSuccessfulTime = that instant (the FMI 2.0 stepFailed state, Step Mode in the table) */
        return fmi2Discard;
    }
    return result(M, status);
}

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, CALL_fmi2CancelStep); }

/* doStep never returns fmi2Pending; it returns fmi2Discard when the model asks to end the simulation.
 * The status queries answer the two kinds an importer asks after a step (last successful time,
 * terminated) and refuse the others. */
/* The entry check and the arguments of a status query that answers one status kind. */
static Status status_query(fmi2Component c, FmiCall call, fmi2StatusKind s, fmi2StatusKind answered,
                           const void *value) {
    if (!cf_enter(M, call)) {
        return ST_ERROR;
    }
    if (value == NULL) {
        return cf_null_argument(M, call, "value");
    }
    if (s != answered) {
        cf_log(M, ST_ERROR, "logStatusError", "%s: status kind %d is not supported by this FMU", cf_call_name(call),
               (int)s);
        return ST_ERROR;
    }
    return ST_OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Status status = status_query(c, CALL_fmi2GetRealStatus, s, fmi2LastSuccessfulTime, value);
    if (status == ST_OK) {
        *value = M->time;
    }
    return result(M, status);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Status status = status_query(c, CALL_fmi2GetBooleanStatus, s, fmi2Terminated, value);
    if (status == ST_OK) {
        *value = M->terminate_requested ? fmi2True : fmi2False;
    }
    return result(M, status);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return unsupported(c, CALL_fmi2GetStatus);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return unsupported(c, CALL_fmi2GetIntegerStatus);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return unsupported(c, CALL_fmi2GetStringStatus);
}
