/* FMI 2.0 co-simulation interface of a cosim plant, on top of cosim_fmu.h. */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "cosim_fmu.h"

#define M ((ModelInstance *)c)
#define ANY_PHASE (PH_MASK(PH_INSTANTIATED) | PH_MASK(PH_INITIALIZATION) | PH_MASK(PH_STEP) | PH_MASK(PH_EVENT) | \
                   PH_MASK(PH_TERMINATED))

static fmi2Status result(ModelInstance *m, Status status) {
    if (status >= ST_ERROR) {
        m->phase = PH_ERROR;
    }
    return (fmi2Status)status;
}

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

static int unsupported(fmi2Component c, const char *fn) {
    if (c != NULL) {
        cf_log(M, ST_ERROR, "logStatusError", "%s is not supported by this FMU", fn);
    }
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    if (c == NULL) {
        return fmi2Error;
    }
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

void fmi2FreeInstance(fmi2Component c) { cf_free(M); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL || !cf_phase_allows(M, "fmi2SetupExperiment", PH_MASK(PH_INSTANTIATED))) {
        return fmi2Error;
    }
    M->start_time = startTime;
    M->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    if (c == NULL || !cf_phase_allows(M, "fmi2EnterInitializationMode", PH_MASK(PH_INSTANTIATED))) {
        return fmi2Error;
    }
    M->phase = PH_INITIALIZATION;
    M->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Status status;
    if (c == NULL || !cf_phase_allows(M, "fmi2ExitInitializationMode", PH_MASK(PH_INITIALIZATION))) {
        return fmi2Error;
    }
    status = cf_exit_init(M);
    if (status <= ST_WARNING) {
        M->phase = PH_STEP;
    }
    return result(M, status);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    if (c == NULL || !cf_phase_allows(M, "fmi2Terminate", PH_MASK(PH_STEP))) {
        return fmi2Error;
    }
    M->phase = PH_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    if (c == NULL) {
        return fmi2Error;
    }
    cf_defaults(M);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    return c == NULL ? fmi2Error : result(M, cf_get(M, VT_FLOAT64, vr, nvr, value, "fmi2GetReal"));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    return c == NULL ? fmi2Error : result(M, cf_get(M, VT_INT32, vr, nvr, value, "fmi2GetInteger"));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    return c == NULL ? fmi2Error : result(M, cf_get(M, VT_BOOL, vr, nvr, value, "fmi2GetBoolean"));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr;
    (void)value;
    if (c == NULL) {
        return fmi2Error;
    }
    if (nvr == 0) {
        return fmi2OK;
    }
    cf_log(M, ST_ERROR, "logStatusError", "fmi2GetString: the model has no String variables");
    return fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    return c == NULL ? fmi2Error : result(M, cf_set(M, VT_FLOAT64, vr, nvr, value, "fmi2SetReal"));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    return c == NULL ? fmi2Error : result(M, cf_set(M, VT_INT32, vr, nvr, value, "fmi2SetInteger"));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    return c == NULL ? fmi2Error : result(M, cf_set(M, VT_BOOL, vr, nvr, value, "fmi2SetBoolean"));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr;
    (void)value;
    if (c == NULL) {
        return fmi2Error;
    }
    if (nvr == 0) {
        return fmi2OK;
    }
    cf_log(M, ST_ERROR, "logStatusError", "fmi2SetString: the model has no String variables");
    return fmi2Error;
}

/* -- FMU state ---------------------------------------------------------------------------------- */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    ModelSnapshot *snap;
    if (c == NULL || state == NULL || !cf_phase_allows(M, "fmi2GetFMUstate", ANY_PHASE)) {
        return fmi2Error;
    }
    snap = (ModelSnapshot *)(*state != NULL ? *state : malloc(sizeof(ModelSnapshot)));
    if (snap == NULL) {
        cf_log(M, ST_ERROR, "logStatusError", "fmi2GetFMUstate: out of memory");
        return fmi2Error;
    }
    snap->phase = M->phase;
    snap->time = M->time;
    snap->v = M->v;
    snap->s = M->s;
    *state = snap;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    const ModelSnapshot *snap = (const ModelSnapshot *)state;
    if (c == NULL || snap == NULL || !cf_phase_allows(M, "fmi2SetFMUstate", ANY_PHASE)) {
        return fmi2Error;
    }
    M->phase = snap->phase;
    M->time = snap->time;
    M->v = snap->v;
    M->s = snap->s;
    M->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    if (c == NULL || state == NULL) {
        return fmi2Error;
    }
    free(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state;
    if (c == NULL || size == NULL) {
        return fmi2Error;
    }
    *size = sizeof(ModelSnapshot);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    if (c == NULL || state == NULL || size < sizeof(ModelSnapshot)) {
        return unsupported(c, "fmi2SerializeFMUstate with a buffer smaller than fmi2SerializedFMUstateSize");
    }
    memcpy(bytes, state, sizeof(ModelSnapshot));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    if (c == NULL || state == NULL || size != sizeof(ModelSnapshot)) {
        return unsupported(c, "fmi2DeSerializeFMUstate of data of another size");
    }
    if (*state == NULL) {
        *state = malloc(sizeof(ModelSnapshot));
    }
    if (*state == NULL) {
        return fmi2Error;
    }
    memcpy(*state, bytes, sizeof(ModelSnapshot));
    return fmi2OK;
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
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

/* -- co-simulation ----------------------------------------------------------------------------- */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    double reached;
    int event;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) {
        return fmi2Error;
    }
    /* FMI 2.0 has no early return: events inside the step are handled by the model itself. */
    M->early_return_allowed = 0;
    return result(M, cf_do_step(M, currentCommunicationPoint, communicationStepSize, &reached, &event));
}

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStatus (doStep never returns fmi2Pending)");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (c == NULL || value == NULL) {
        return fmi2Error;
    }
    if (s == fmi2LastSuccessfulTime) {
        *value = M->time;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetRealStatus for this status kind");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    if (c == NULL || value == NULL) {
        return fmi2Error;
    }
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetBooleanStatus for this status kind");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
