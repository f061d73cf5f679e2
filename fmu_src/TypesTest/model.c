/* TypesTest: a test model for FMU importers (cosim's adapter and master are tested against it).
 *
 * Every output of a type copies the input of that type (vec_out doubles vec_in; matrix_out is a
 * constant whose elements show the row-major order), position integrates speed, and three instants
 * set by parameters exercise the importer:
 *
 *   stage_time      event_stage goes from 1 to 2: a time event. With early return (FMI 3.0) doStep
 *                   stops there; with event mode the stage changes in fmi3UpdateDiscreteStates.
 *   terminate_time  the model asks to end the simulation: doStep stops there and reports
 *                   terminateSimulation (FMI 3.0) or returns fmi2Discard with fmi2Terminated (FMI 2.0);
 *                   with terminate_in_event_mode (FMI 3.0, event mode) the request comes from
 *                   fmi3UpdateDiscreteStates after an early return there.
 *   error_time      doStep fails there with an Error status and a log message.
 *
 * 0 disables terminate_time and error_time. An instant counts as reached by a step that ends within
 * floating-point noise of it, and the step then stops exactly at it. */
#include <math.h>
#include <string.h>

#include "cosim_fmu.h"

enum { NONE, STAGE, TERMINATE, FAIL };

/* Steps ending within this of an instant [s] reach it (floating-point noise of the importer's sums). */
static double noise(double t) { return 1e-12 * (1.0 + fabs(t)); }

Status model_init(ModelInstance *m) {
    m->s.position = 0.0;
    m->s.stage = m->v.stage_time <= m->time ? 2 : 1;
    m->s.pending_stage = 0;
    m->s.pending_terminate = 0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    ModelData *v = &m->v;
    int i, j;
    v->position = m->s.position;
    v->event_stage = m->s.stage;
    v->f32_out = v->f32_in;
    v->i8_out = v->i8_in;
    v->u8_out = v->u8_in;
    v->i16_out = v->i16_in;
    v->u16_out = v->u16_in;
    v->i32_out = v->i32_in;
    v->u32_out = v->u32_in;
    v->i64_out = v->i64_in;
    v->u64_out = v->u64_in;
    v->flag_out = v->flag_in;
    memcpy(v->text_out, v->text_in, sizeof(v->text_out));
    v->blob_out = v->blob_in;
    v->mode_out = v->mode_in;
    for (i = 0; i < N_VEC_IN; i++) {
        v->vec_out[i] = 2.0 * v->vec_in[i];
    }
    for (i = 0; i < 2; i++) {
        for (j = 0; j < 3; j++) {
            v->matrix_out[3 * i + j] = (int16_t)(10 * i + j);
        }
    }
}

/* The first instant still to come in [t, t_end], and what happens there (NONE: *at = t_end). */
static int next_instant(const ModelInstance *m, double t, double t_end, double *at) {
    const double limit = t_end + noise(t_end);
    int what = NONE;
    *at = t_end;
    if (m->s.stage == 1 && !m->s.pending_stage && m->v.stage_time <= limit) {
        what = STAGE;
        *at = m->v.stage_time;
    }
    if (m->v.terminate_time > 0.0 && !m->s.pending_terminate && m->v.terminate_time <= limit &&
        (what == NONE || m->v.terminate_time < *at)) {
        what = TERMINATE;
        *at = m->v.terminate_time;
    }
    if (m->v.error_time > 0.0 && m->v.error_time <= limit && (what == NONE || m->v.error_time < *at)) {
        what = FAIL;
        *at = m->v.error_time;
    }
    if (*at > t_end) {
        *at = t_end;
    }
    if (*at < t) {
        *at = t;
    }
    return what;
}

static void ask_to_terminate(ModelInstance *m) {
    m->terminate_requested = 1;
    cf_log(m, ST_WARNING, "logStatusWarning", "terminate_time = %.17g s reached: the model asks to end the simulation",
           m->v.terminate_time);
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    double t = m->time, at;
    *event = 0;
    *t_reached = t_end;
    if (m->s.pending_stage) { /* an importer that skipped event mode: apply the event now */
        m->s.stage = 2;
        m->s.pending_stage = 0;
    }
    for (;;) {
        const int what = next_instant(m, t, t_end, &at);
        m->s.position += m->v.speed * (at - t);
        t = at;
        switch (what) {
        case STAGE:
            if (m->early_return_allowed) {
                *t_reached = t;
                *event = 1;
                if (m->event_mode_used) {
                    m->s.pending_stage = 1;
                } else {
                    m->s.stage = 2;
                }
                return ST_OK;
            }
            m->s.stage = 2;
            break;
        case TERMINATE:
            *t_reached = t;
            if (m->v.terminate_in_event_mode && m->event_mode_used && m->early_return_allowed) {
                m->s.pending_terminate = 1;
                *event = 1;
            } else {
                ask_to_terminate(m);
            }
            return ST_OK;
        case FAIL:
            cf_log(m, ST_ERROR, "logStatusError", "error_time = %.17g s reached: the model fails here as asked",
                   m->v.error_time);
            return ST_ERROR;
        case NONE:
        default:
            return ST_OK;
        }
    }
}

Status model_event_update(ModelInstance *m, int *again) {
    if (m->s.pending_stage) {
        m->s.stage = 2;
        m->s.pending_stage = 0;
    }
    if (m->s.pending_terminate) {
        ask_to_terminate(m);
    }
    *again = 0;
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) {
    (void)m;
    (void)z;
}
