/* Shared helpers of the cosim plant FMUs: instances, typed access with range checks, stepping,
 * FMU state snapshots. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cosim_fmu.h"

static const char *const CAUSALITY_NAME[] = {"independent", "parameter", "calculated parameter",
                                             "input", "output", "local"};
static const char *const TYPE_NAME[] = {"Float64", "Int32", "Boolean"};

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

static const VarDef *find_var(ModelInstance *m, unsigned vr, VarType type, const char *fn) {
    size_t i;
    for (i = 0; i < N_MODEL_VARS; i++) {
        if (MODEL_VARS[i].vr == vr) {
            if (MODEL_VARS[i].type != type) {
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

static void *field(ModelInstance *m, const VarDef *d) { return (char *)&m->v + d->offset; }

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

/* 1 if value is allowed for d; logs the reason otherwise. */
static int check_value(ModelInstance *m, const VarDef *d, double value) {
    char range[128];
    int ok = 1;
    if (d->type == VT_FLOAT64 && !isfinite(value)) {
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

static double as_double(const VarDef *d, const void *p) {
    switch (d->type) {
    case VT_FLOAT64:
        return *(const double *)p;
    case VT_INT32:
        return (double)*(const int32_t *)p;
    case VT_BOOL:
    default:
        return (double)*(const int *)p;
    }
}

static Status check_all(ModelInstance *m) {
    size_t i;
    for (i = 0; i < N_MODEL_VARS; i++) {
        const VarDef *d = &MODEL_VARS[i];
        if ((d->causality == CA_PARAMETER || d->causality == CA_INPUT) &&
            !check_value(m, d, as_double(d, field(m, d)))) {
            return ST_ERROR;
        }
    }
    return model_check(m);
}

Status cf_get(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t n, void *values) {
    const char *fn = cf_call_name(call);
    size_t i;
    if (n > 0 && (vr == NULL || values == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : "values");
    }
    if (m->outputs_stale && m->phase != PH_INSTANTIATED) {
        model_outputs(m);
        m->outputs_stale = 0;
    }
    for (i = 0; i < n; i++) {
        const VarDef *d = find_var(m, vr[i], type, fn);
        if (d == NULL) {
            return ST_ERROR;
        }
        if (d->causality == CA_INDEPENDENT) {
            ((double *)values)[i] = m->time;
            continue;
        }
        switch (type) {
        case VT_FLOAT64:
            ((double *)values)[i] = *(double *)field(m, d);
            break;
        case VT_INT32:
            ((int32_t *)values)[i] = *(int32_t *)field(m, d);
            break;
        case VT_BOOL:
            ((int *)values)[i] = *(int *)field(m, d);
            break;
        }
    }
    return ST_OK;
}

Status cf_set(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t n, const void *values) {
    const char *fn = cf_call_name(call);
    size_t i;
    if (n > 0 && (vr == NULL || values == NULL)) {
        return cf_null_argument(m, call, vr == NULL ? "vr" : "values");
    }
    for (i = 0; i < n; i++) {
        const VarDef *d = find_var(m, vr[i], type, fn);
        double value;
        if (d == NULL) {
            return ST_ERROR;
        }
        if (d->causality != CA_PARAMETER && d->causality != CA_INPUT) {
            cf_log(m, ST_ERROR, "logStatusError", "%s: %s is an %s and cannot be set", fn, d->name,
                   CAUSALITY_NAME[d->causality]);
            return ST_ERROR;
        }
        if (d->causality == CA_PARAMETER && !d->tunable &&
            (m->phase == PH_STEP || m->phase == PH_EVENT)) {
            cf_log(m, ST_ERROR, "logStatusError", "%s: parameter %s is fixed after initialisation", fn, d->name);
            return ST_ERROR;
        }
        switch (type) {
        case VT_FLOAT64:
            value = ((const double *)values)[i];
            break;
        case VT_INT32:
            value = (double)((const int32_t *)values)[i];
            break;
        case VT_BOOL:
        default:
            value = ((const int *)values)[i] ? 1.0 : 0.0;
            break;
        }
        if (!check_value(m, d, value)) {
            return ST_ERROR;
        }
        switch (type) {
        case VT_FLOAT64:
            *(double *)field(m, d) = value;
            break;
        case VT_INT32:
            *(int32_t *)field(m, d) = ((const int32_t *)values)[i];
            break;
        case VT_BOOL:
            *(int *)field(m, d) = ((const int *)values)[i] ? 1 : 0;
            break;
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
