/* FMI 2.0 co-simulation interface of an exported machine (on top of machine.h).
 *
 * FMI 2.0 has neither early return nor event mode: fmi2DoStep runs every event up to the end of
 * the step, and the outputs hold their values after the events of that instant. */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "machine.h"

#define M ((Machine *)c)
#define ALL (PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP | PH_TERMINATED | PH_ERROR)
#define ENTER(fn, allowed)                                                                                            \
    do {                                                                                                              \
        if (!machine_enter(M, #fn, allowed)) {                                                                        \
            return fmi2Error;                                                                                         \
        }                                                                                                             \
    } while (0)

/* The FMI 2.0 logger takes a printf format. Importers written in other languages often cannot read
 * variadic arguments, so the message itself is the format, with any '%' doubled. */
static void sink(const Machine *m, MStatus status, const char *category, const char *message) {
    const fmi2CallbackFunctions *cb = (const fmi2CallbackFunctions *)m->callbacks;
    char format[4096];
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
    cb->logger(cb->componentEnvironment, m->name, (fmi2Status)status, category, format);
}

static fmi2Status unsupported(fmi2Component c, const char *fn) { return (fmi2Status)machine_unsupported(M, fn); }

/* A file URI (file:///a/b or file:/a/b, %XX escapes) as a path; NULL if it is not one. */
static char *uri_to_path(const char *uri) {
    const char *p;
    char *path, *out;
    if (uri == NULL || strncmp(uri, "file:", 5) != 0) {
        return NULL;
    }
    p = uri + 5;
    if (strncmp(p, "///", 3) == 0) {
        p += 2;
    } else if (strncmp(p, "//localhost/", 12) == 0) {
        p += 11;
    }
    path = out = (char *)malloc(strlen(p) + 1);
    if (path == NULL) {
        return NULL;
    }
    while (*p != '\0') {
        if (p[0] == '%' && p[1] != '\0' && p[2] != '\0') {
            char hex[3] = {p[1], p[2], '\0'};
            *out++ = (char)strtol(hex, NULL, 16);
            p += 3;
        } else {
            *out++ = *p++;
        }
    }
    *out = '\0';
    return path;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    ENTER(fmi2SetDebugLogging, ALL);
    M->logging_on = loggingOn ? 1 : 0;
    return (fmi2Status)machine_call(M, "set_debug_logging", "(i)", M->logging_on);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    Machine *m;
    char *resources;
    (void)visible;
    if (functions == NULL || functions->logger == NULL) {
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                          "model exchange is not supported: a machine is a co-simulation FMU");
        return NULL;
    }
    resources = uri_to_path(fmuResourceLocation);
    if (resources == NULL) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                          "the resource location is not a file URI");
        return NULL;
    }
    m = machine_new(2, instanceName, fmuGUID, resources, sink, functions->componentEnvironment, functions, NULL,
                    loggingOn ? 1 : 0, 0, 0);
    free(resources);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { machine_free(M); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    ENTER(fmi2SetupExperiment, PH_INSTANTIATED);
    M->start_time = startTime;
    M->stop_time = stopTime;
    M->stop_defined = stopTimeDefined ? 1 : 0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    fmi2Status status;
    ENTER(fmi2EnterInitializationMode, PH_INSTANTIATED);
    status = (fmi2Status)machine_call(M, "enter_initialization", "(did)", M->start_time, M->stop_defined,
                                      M->stop_time);
    if (status <= fmi2Warning) {
        M->phase = PH_INITIALIZATION;
    }
    return status;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    fmi2Status status;
    ENTER(fmi2ExitInitializationMode, PH_INITIALIZATION);
    status = (fmi2Status)machine_call(M, "exit_initialization", "()");
    if (status <= fmi2Warning) {
        M->phase = PH_STEP;
    }
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    fmi2Status status;
    ENTER(fmi2Terminate, PH_STEP);
    status = (fmi2Status)machine_call(M, "terminate", "()");
    if (status <= fmi2Warning) {
        M->phase = PH_TERMINATED;
    }
    return status;
}

fmi2Status fmi2Reset(fmi2Component c) {
    fmi2Status status;
    ENTER(fmi2Reset, ALL);
    status = (fmi2Status)machine_call(M, "reset", "()");
    if (status <= fmi2Warning) {
        M->phase = PH_INSTANTIATED;
    }
    return status;
}

/* -- variables ---------------------------------------------------------------------------------- */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    ENTER(fmi2GetReal, PH_INITIALIZATION | PH_STEP | PH_TERMINATED | PH_ERROR);
    return (fmi2Status)machine_get(M, "fmi2GetReal", VK_FLOAT64, vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    ENTER(fmi2GetInteger, PH_INITIALIZATION | PH_STEP | PH_TERMINATED | PH_ERROR);
    return (fmi2Status)machine_get(M, "fmi2GetInteger", VK_INT32, vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    ENTER(fmi2GetBoolean, PH_INITIALIZATION | PH_STEP | PH_TERMINATED | PH_ERROR);
    return (fmi2Status)machine_get(M, "fmi2GetBoolean", VK_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)vr;
    (void)value;
    ENTER(fmi2GetString, ALL);
    if (nvr == 0) {
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetString");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    ENTER(fmi2SetReal, PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP);
    return (fmi2Status)machine_set(M, "fmi2SetReal", VK_FLOAT64, vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    ENTER(fmi2SetInteger, PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP);
    return (fmi2Status)machine_set(M, "fmi2SetInteger", VK_INT32, vr, nvr, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    ENTER(fmi2SetBoolean, PH_INSTANTIATED | PH_INITIALIZATION | PH_STEP);
    return (fmi2Status)machine_set(M, "fmi2SetBoolean", VK_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)vr;
    (void)value;
    ENTER(fmi2SetString, ALL);
    if (nvr == 0) {
        return fmi2OK;
    }
    return unsupported(c, "fmi2SetString");
}

/* -- FMU state, derivatives: not offered -------------------------------------------------------- */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return unsupported(c, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    return unsupported(c, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return unsupported(c, "fmi2FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state;
    (void)size;
    return unsupported(c, "fmi2SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)state;
    (void)bytes;
    (void)size;
    return unsupported(c, "fmi2SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    (void)bytes;
    (void)size;
    (void)state;
    return unsupported(c, "fmi2DeSerializeFMUstate");
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

/* -- stepping ----------------------------------------------------------------------------------- */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER(fmi2DoStep, PH_STEP);
    return (fmi2Status)machine_call(M, "do_step", "(dd)", currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

/* doStep never returns fmi2Pending or fmi2Discard: the queries answer the last successful time
 * and "not terminated", and refuse the other kinds. */
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    ENTER(fmi2GetRealStatus, PH_STEP | PH_TERMINATED);
    if (s != fmi2LastSuccessfulTime || value == NULL) {
        return unsupported(c, "fmi2GetRealStatus (other than fmi2LastSuccessfulTime)");
    }
    *value = M->step[SR_LAST_TIME];
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    ENTER(fmi2GetBooleanStatus, PH_STEP | PH_TERMINATED);
    if (s != fmi2Terminated || value == NULL) {
        return unsupported(c, "fmi2GetBooleanStatus (other than fmi2Terminated)");
    }
    *value = M->step[SR_TERMINATE] != 0.0 ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
