/* Shared helpers of the cosim plant FMUs: instances, typed access with range checks, stepping,
 * FMU state snapshots. */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cosim_fmu.h"

static const char *const CAUSALITY_NAME[] = {"independent", "parameter", "calculated parameter",
                                             "input", "output", "local"};
static const char *const TYPE_NAME[N_VAR_TYPES] = {
    [VT_FLOAT64] = "Float64", [VT_INT32] = "Int32",   [VT_BOOL] = "Boolean",  [VT_FLOAT32] = "Float32",
    [VT_INT8] = "Int8",       [VT_UINT8] = "UInt8",   [VT_INT16] = "Int16",   [VT_UINT16] = "UInt16",
    [VT_UINT32] = "UInt32",   [VT_INT64] = "Int64",   [VT_UINT64] = "UInt64", [VT_STRING] = "String",
    [VT_BINARY] = "Binary",   [VT_ENUM] = "Enumeration", [VT_BOOL_C] = "Boolean"};

ModelInstance *cf_new(const char *instance_name) {
    ModelInstance *m = (ModelInstance *)calloc(1, sizeof(ModelInstance));
    if (m == NULL) {
        return NULL;
    }
    const char *name = instance_name != NULL ? instance_name : "";
    m->instance_name = (char *)malloc(strlen(name) + 1);
    if (m->instance_name == NULL) {
        free(m);
        return NULL;
    }
    strcpy(m->instance_name, name);
    cf_defaults(m);
    return m;
}

void cf_free(ModelInstance *m) {
    if (m != NULL) {
        free(m->instance_name);
        free(m);
    }
}

void cf_defaults(ModelInstance *m) {
    memset(&m->s, 0, sizeof(m->s));
    model_vars_defaults(&m->v);
    m->phase = PH_INSTANTIATED;
    m->start_time = 0.0;
    m->time = 0.0;
    m->outputs_stale = 1;
    m->terminate_requested = 0;
}

void cf_log(ModelInstance *m, Status status, const char *category, const char *fmt, ...) {
    char message[1024];
    va_list args;
    if (m == NULL || m->log_sink == NULL) {
        return;
    }
    if (status == ST_OK && !m->logging_on) {
        return; /* debug messages only when asked for; warnings and errors always */
    }
    va_start(args, fmt);
    vsnprintf(message, sizeof(message), fmt, args);
    va_end(args);
    m->log_sink(m, status, category, message);
}

Status cf_result(ModelInstance *m, Status status) {
    if (m != NULL && status == ST_FATAL) {
        m->phase = PH_FATAL;
    } else if (m != NULL && status == ST_ERROR && m->phase != PH_FATAL) {
        m->phase = PH_ERROR;
    }
    return status;
}

Status cf_null_argument(ModelInstance *m, FmiCall call, const char *argument) {
    cf_log(m, ST_ERROR, "logStatusError", "%s: argument %s must not be NULL", cf_call_name(call), argument);
    return ST_ERROR;
}

Status cf_unsupported(ModelInstance *m, FmiCall call) {
    cf_log(m, ST_ERROR, "logStatusError", "%s is not supported by this FMU", cf_call_name(call));
    return ST_ERROR;
}

Status cf_no_vars(ModelInstance *m, FmiCall call, size_t n) {
    if (n == 0) {
        return ST_OK;
    }
    cf_log(m, ST_ERROR, "logStatusError", "%s: the model has no variables of this type", cf_call_name(call));
    return ST_ERROR;
}

/* 1 if a variable stored as `stored` can be reached through a getter/setter of `access`. */
static int reachable(VarType stored, VarType access) {
    return stored == access || (stored == VT_BOOL && access == VT_BOOL_C) ||
           (stored == VT_ENUM && (access == VT_INT32 || access == VT_INT64));
}

static const VarDef *find_var(ModelInstance *m, unsigned vr, VarType type, const char *fn) {
    size_t i;
    for (i = 0; i < N_MODEL_VARS; i++) {
        if (MODEL_VARS[i].vr == vr) {
            if (!reachable(MODEL_VARS[i].type, type)) {
                cf_log(m, ST_ERROR, "logStatusError", "%s: variable %s (value reference %u) is %s, not %s", fn,
                       MODEL_VARS[i].name, vr, TYPE_NAME[MODEL_VARS[i].type], TYPE_NAME[type]);
                return NULL;
            }
            return &MODEL_VARS[i];
        }
    }
    cf_log(m, ST_ERROR, "logStatusError", "%s: unknown value reference %u", fn, vr);
    return NULL;
}

/* Bytes one element of a variable of this type takes in ModelData. */
static size_t stored_size(VarType type) {
    switch (type) {
    case VT_FLOAT32:
        return sizeof(float);
    case VT_INT8:
    case VT_UINT8:
        return 1;
    case VT_INT16:
    case VT_UINT16:
        return 2;
    case VT_INT32:
    case VT_UINT32:
        return 4;
    case VT_INT64:
    case VT_UINT64:
    case VT_ENUM:
        return 8;
    case VT_BOOL:
        return sizeof(int);
    case VT_BOOL_C:
        return sizeof(bool);
    case VT_STRING:
        return CF_STRING_CAPACITY;
    case VT_BINARY:
        return sizeof(CfBinary);
    case VT_FLOAT64:
    default:
        return sizeof(double);
    }
}

/* Bytes one element takes in the importer's values array. */
static size_t access_size(VarType type) { return type == VT_STRING ? sizeof(const char *) : stored_size(type); }

static void *element(ModelInstance *m, const VarDef *d, size_t j) {
    return (char *)&m->v + d->offset + j * stored_size(d->type);
}

/* Every FMU checks that the importer's values array has one element per element of its variables. */
static int count_values(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t nvr,
                        size_t nValues) {
    size_t i, total = 0;
    for (i = 0; i < nvr; i++) {
        const VarDef *d = find_var(m, vr[i], type, cf_call_name(call));
        if (d == NULL) {
            return 0;
        }
        total += d->n;
    }
    if (total != nValues) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: nValues = %lu is not allowed (allowed: %lu, the elements of the "
               "%lu variables asked for)", cf_call_name(call), (unsigned long)nValues, (unsigned long)total,
               (unsigned long)nvr);
        return 0;
    }
    return 1;
}

static void describe_range(const VarDef *d, char *buf, size_t size) {
    if (d->positive && d->has_max) {
        snprintf(buf, size, "> 0 and <= %.17g", d->max);
    } else if (d->positive) {
        snprintf(buf, size, "> 0");
    } else if (d->has_min && d->has_max) {
        snprintf(buf, size, "%.17g..%.17g", d->min, d->max);
    } else if (d->has_min) {
        snprintf(buf, size, ">= %.17g", d->min);
    } else if (d->has_max) {
        snprintf(buf, size, "<= %.17g", d->max);
    } else {
        snprintf(buf, size, "any finite value");
    }
}

/* 1 if value is allowed for d; logs the reason otherwise. (64-bit integers are compared as doubles:
 * exact for limits up to 2^53.) */
static int check_value(ModelInstance *m, const VarDef *d, double value) {
    char range[128];
    int ok = 1;
    if ((d->type == VT_FLOAT64 || d->type == VT_FLOAT32) && !isfinite(value)) {
        ok = 0;
    }
    if (d->has_min && value < d->min) {
        ok = 0;
    }
    if (d->has_max && value > d->max) {
        ok = 0;
    }
    if (d->positive && !(value > 0.0)) {
        ok = 0;
    }
    if (!ok) {
        describe_range(d, range, sizeof(range));
        cf_log(m, ST_ERROR, "logStatusError", "%s %s = %.17g%s%s is not allowed (allowed: %s%s%s)",
               CAUSALITY_NAME[d->causality], d->name, value, d->unit[0] ? " " : "", d->unit, range,
               d->unit[0] ? " " : "", d->unit);
    }
    return ok;
}

/* A numeric or Boolean element as a double, for the range checks (Strings and Binaries: 0). */
static double as_double(VarType type, const void *p) {
    switch (type) {
    case VT_FLOAT64:
        return *(const double *)p;
    case VT_FLOAT32:
        return (double)*(const float *)p;
    case VT_INT8:
        return (double)*(const int8_t *)p;
    case VT_UINT8:
        return (double)*(const uint8_t *)p;
    case VT_INT16:
        return (double)*(const int16_t *)p;
    case VT_UINT16:
        return (double)*(const uint16_t *)p;
    case VT_INT32:
        return (double)*(const int32_t *)p;
    case VT_UINT32:
        return (double)*(const uint32_t *)p;
    case VT_INT64:
    case VT_ENUM:
        return (double)*(const int64_t *)p;
    case VT_UINT64:
        return (double)*(const uint64_t *)p;
    case VT_BOOL:
        return *(const int *)p ? 1.0 : 0.0;
    case VT_BOOL_C:
        return *(const bool *)p ? 1.0 : 0.0;
    case VT_STRING:
    case VT_BINARY:
    default:
        return 0.0;
    }
}

static Status check_all(ModelInstance *m) {
    size_t i, j;
    for (i = 0; i < N_MODEL_VARS; i++) {
        const VarDef *d = &MODEL_VARS[i];
        if (d->causality != CA_PARAMETER && d->causality != CA_INPUT) {
            continue;
        }
        for (j = 0; j < d->n; j++) {
            if (!check_value(m, d, as_double(d->type, element(m, d, j)))) {
                return ST_ERROR;
            }
        }
    }
    return model_check(m);
}

/* Stored element `from` of d to the importer's element `to` of type `access`. */
static void copy_out(const VarDef *d, const void *from, VarType access, void *to) {
    if (d->type == VT_BOOL && access == VT_BOOL_C) {
        *(bool *)to = *(const int *)from != 0;
    } else if (d->type == VT_ENUM && access == VT_INT32) { /* FMI 2.0 Enumeration: in range by its check */
        *(int32_t *)to = (int32_t)*(const int64_t *)from;
    } else if (access == VT_STRING) {
        *(const char **)to = (const char *)from;
    } else {
        memcpy(to, from, stored_size(access));
    }
}

/* The importer's element `from` of type `access` to stored element `to` of d; 0 (logged) if refused. */
static int copy_in(ModelInstance *m, const VarDef *d, const void *from, VarType access, void *to) {
    if (access == VT_STRING) {
        const char *text = *(const char *const *)from;
        size_t length;
        if (text == NULL) {
            text = "";
        }
        length = strlen(text);
        if (length >= CF_STRING_CAPACITY) {
            cf_log(m, ST_ERROR, "logStatusError", "%s %s: a string of %lu bytes is not allowed (allowed: up to %d)",
                   CAUSALITY_NAME[d->causality], d->name, (unsigned long)length, CF_STRING_CAPACITY - 1);
            return 0;
        }
        memcpy(to, text, length + 1);
        return 1;
    }
    if (!check_value(m, d, as_double(access, from))) {
        return 0;
    }
    if (d->type == VT_BOOL) {
        *(int *)to = as_double(access, from) != 0.0 ? 1 : 0;
    } else if (d->type == VT_ENUM && access == VT_INT32) {
        *(int64_t *)to = (int64_t)*(const int32_t *)from;
    } else {
        memcpy(to, from, stored_size(access));
    }
    return 1;
}

/* An error unless d may be set in the instance's state. */
static int settable(ModelInstance *m, const VarDef *d, const char *fn) {
    if (d->causality != CA_PARAMETER && d->causality != CA_INPUT) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: %s is an %s and cannot be set", fn, d->name,
               CAUSALITY_NAME[d->causality]);
        return 0;
    }
    if (d->causality == CA_PARAMETER && !d->tunable && (m->phase == PH_STEP || m->phase == PH_EVENT)) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: parameter %s is fixed after initialisation", fn, d->name);
        return 0;
    }
    return 1;
}

static void refresh_outputs(ModelInstance *m) {
    if (m->outputs_stale && m->phase != PH_INSTANTIATED) {
        model_outputs(m);
        m->outputs_stale = 0;
    }
}

Status cf_get(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t nvr, void *values,
              size_t nValues) {
    const char *fn = cf_call_name(call);
    size_t i, j, k = 0;
    if (nvr > 0 && (vr == NULL || values == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : "values");
    }
    if (!count_values(m, call, type, vr, nvr, nValues)) {
        return ST_ERROR;
    }
    refresh_outputs(m);
    for (i = 0; i < nvr; i++) {
        const VarDef *d = find_var(m, vr[i], type, fn);
        if (d->causality == CA_INDEPENDENT) {
            ((double *)values)[k++] = m->time;
            continue;
        }
        for (j = 0; j < d->n; j++, k++) {
            copy_out(d, element(m, d, j), type, (char *)values + k * access_size(type));
        }
    }
    return ST_OK;
}

Status cf_set(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t nvr, const void *values,
              size_t nValues) {
    const char *fn = cf_call_name(call);
    size_t i, j, k = 0;
    if (nvr > 0 && (vr == NULL || values == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : "values");
    }
    if (!count_values(m, call, type, vr, nvr, nValues)) {
        return ST_ERROR;
    }
    for (i = 0; i < nvr; i++) {
        const VarDef *d = find_var(m, vr[i], type, fn);
        if (!settable(m, d, fn)) {
            return ST_ERROR;
        }
        for (j = 0; j < d->n; j++, k++) {
            if (!copy_in(m, d, (const char *)values + k * access_size(type), type, element(m, d, j))) {
                return ST_ERROR;
            }
        }
        m->outputs_stale = 1;
    }
    return ST_OK;
}

Status cf_get_binary(ModelInstance *m, FmiCall call, const unsigned *vr, size_t nvr, size_t *sizes,
                     const unsigned char **values, size_t nValues) {
    const char *fn = cf_call_name(call);
    size_t i, j, k = 0;
    if (nvr > 0 && (vr == NULL || values == NULL || sizes == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : values == NULL ? "values" : "valueSizes");
    }
    if (!count_values(m, call, VT_BINARY, vr, nvr, nValues)) {
        return ST_ERROR;
    }
    refresh_outputs(m);
    for (i = 0; i < nvr; i++) {
        const VarDef *d = find_var(m, vr[i], VT_BINARY, fn);
        for (j = 0; j < d->n; j++, k++) {
            const CfBinary *b = (const CfBinary *)element(m, d, j);
            sizes[k] = b->size;
            values[k] = b->data;
        }
    }
    return ST_OK;
}

Status cf_set_binary(ModelInstance *m, FmiCall call, const unsigned *vr, size_t nvr, const size_t *sizes,
                     const unsigned char *const *values, size_t nValues) {
    const char *fn = cf_call_name(call);
    size_t i, j, k = 0;
    if (nvr > 0 && (vr == NULL || values == NULL || sizes == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : values == NULL ? "values" : "valueSizes");
    }
    if (!count_values(m, call, VT_BINARY, vr, nvr, nValues)) {
        return ST_ERROR;
    }
    for (i = 0; i < nvr; i++) {
        const VarDef *d = find_var(m, vr[i], VT_BINARY, fn);
        if (!settable(m, d, fn)) {
            return ST_ERROR;
        }
        for (j = 0; j < d->n; j++, k++) {
            CfBinary *b = (CfBinary *)element(m, d, j);
            if (sizes[k] > CF_BINARY_CAPACITY || (sizes[k] > 0 && values[k] == NULL)) {
                cf_log(m, ST_ERROR, "logStatusError", "%s %s: a value of %lu bytes is not allowed (allowed: up to %d)",
                       CAUSALITY_NAME[d->causality], d->name, (unsigned long)sizes[k], CF_BINARY_CAPACITY);
                return ST_ERROR;
            }
            b->size = sizes[k];
            if (sizes[k] > 0) {
                memcpy(b->data, values[k], sizes[k]);
            }
        }
        m->outputs_stale = 1;
    }
    return ST_OK;
}

Status cf_exit_init(ModelInstance *m) {
    Status status = check_all(m);
    if (status > ST_WARNING) {
        return status;
    }
    status = model_init(m);
    if (status > ST_WARNING) {
        return status;
    }
    model_outputs(m);
    m->outputs_stale = 0;
    return status;
}

Status cf_do_step(ModelInstance *m, FmiCall call, double t_comm, double h, double *t_reached, int *event) {
    double tolerance = 1e-10 * (1.0 + fabs(m->time));
    Status status;
    *event = 0;
    *t_reached = m->time;
    if (!(h >= 0.0) || !isfinite(h)) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: communicationStepSize = %.17g is not allowed (allowed: >= 0 s)",
               cf_call_name(call), h);
        return ST_ERROR;
    }
    if (m->terminate_requested) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: the model asked to end the simulation at t = %.17g s; "
               "terminate the instance", cf_call_name(call), m->time);
        return ST_ERROR;
    }
    if (fabs(t_comm - m->time) > tolerance) {
        cf_log(m, ST_ERROR, "logStatusError",
               "%s: currentCommunicationPoint = %.17g s does not match the instance's time %.17g s",
               cf_call_name(call), t_comm, m->time);
        return ST_ERROR;
    }
    m->time = t_comm;
    status = model_step(m, t_comm + h, t_reached, event);
    if (status <= ST_WARNING) {
        m->time = *t_reached;
        model_outputs(m);
        m->outputs_stale = 0;
    }
    return status;
}

Status cf_event_indicators(ModelInstance *m, FmiCall call, double *z, size_t n) {
    if (n != N_EVENT_INDICATORS) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: asked for %lu indicators, the model has %d", cf_call_name(call),
               (unsigned long)n, N_EVENT_INDICATORS);
        return ST_ERROR;
    }
    if (n > 0) {
        model_event_indicators(m, z);
    }
    return ST_OK;
}

/* -- FMU state -------------------------------------------------------------------------------- */
/* Everything a snapshot holds: the plain data of the instance (no pointers). */
typedef struct {
    Phase phase;
    double time;
    int terminate_requested;
    ModelData v;
    ModelState s;
} ModelSnapshot;

Status cf_state_get(ModelInstance *m, FmiCall call, void **state) {
    ModelSnapshot *snap;
    if (state == NULL) {
        return cf_null_argument(m, call, "FMUState");
    }
    snap = (ModelSnapshot *)(*state != NULL ? *state : malloc(sizeof(ModelSnapshot)));
    if (snap == NULL) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: out of memory", cf_call_name(call));
        return ST_ERROR;
    }
    snap->phase = m->phase;
    snap->time = m->time;
    snap->terminate_requested = m->terminate_requested;
    snap->v = m->v;
    snap->s = m->s;
    *state = snap;
    return ST_OK;
}

Status cf_state_set(ModelInstance *m, FmiCall call, const void *state) {
    const ModelSnapshot *snap = (const ModelSnapshot *)state;
    if (snap == NULL) {
        return cf_null_argument(m, call, "FMUState");
    }
    m->phase = snap->phase;
    m->time = snap->time;
    m->terminate_requested = snap->terminate_requested;
    m->v = snap->v;
    m->s = snap->s;
    m->outputs_stale = 1;
    return ST_OK;
}

Status cf_state_free(ModelInstance *m, FmiCall call, void **state) {
    if (state == NULL) {
        return cf_null_argument(m, call, "FMUState");
    }
    free(*state);
    *state = NULL;
    return ST_OK;
}

Status cf_state_size(ModelInstance *m, FmiCall call, size_t *size) {
    if (size == NULL) {
        return cf_null_argument(m, call, "size");
    }
    *size = sizeof(ModelSnapshot);
    return ST_OK;
}

Status cf_state_serialize(ModelInstance *m, FmiCall call, const void *state, unsigned char *bytes, size_t size) {
    if (state == NULL || bytes == NULL) {
        return cf_null_argument(m, call, state == NULL ? "FMUState" : "serializedState");
    }
    if (size < sizeof(ModelSnapshot)) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: size = %lu is not allowed (allowed: >= %lu, the serialized size)",
               cf_call_name(call), (unsigned long)size, (unsigned long)sizeof(ModelSnapshot));
        return ST_ERROR;
    }
    memcpy(bytes, state, sizeof(ModelSnapshot));
    return ST_OK;
}

Status cf_state_deserialize(ModelInstance *m, FmiCall call, const unsigned char *bytes, size_t size, void **state) {
    if (state == NULL || bytes == NULL) {
        return cf_null_argument(m, call, state == NULL ? "FMUState" : "serializedState");
    }
    if (size != sizeof(ModelSnapshot)) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: size = %lu is not allowed (allowed: %lu, the serialized size)",
               cf_call_name(call), (unsigned long)size, (unsigned long)sizeof(ModelSnapshot));
        return ST_ERROR;
    }
    if (*state == NULL) {
        *state = malloc(sizeof(ModelSnapshot));
    }
    if (*state == NULL) {
        cf_log(m, ST_ERROR, "logStatusError", "%s: out of memory", cf_call_name(call));
        return ST_ERROR;
    }
    memcpy(*state, bytes, sizeof(ModelSnapshot));
    return ST_OK;
}
