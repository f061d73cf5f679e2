/* BouncingBall (bench model): der(h) = v, der(v) = g, forward Euler on the internal grid t0 + k h
 * (h = 1e-3 s). An internal step that ends with the ball at or below the floor, falling, is a
 * bounce: h = 0, v = -e v (below V_MIN the ball rests). With FMI 3.0 early return the doStep stops
 * there; with event mode the bounce is applied in fmi3UpdateDiscreteStates. */
#include "cosim_fmu.h"
#include "grid.h"

#define SOLVER_STEP 1e-3
#define V_MIN 0.1

Status model_init(ModelInstance *m) {
    m->s.h = 1.0;
    m->s.v = 0.0;
    m->s.resting = 0;
    m->s.pending = 0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    m->v.h = m->s.h;
    m->v.v = m->s.v;
}

static void bounce(ModelInstance *m) {
    m->s.h = 0.0;
    m->s.v = -m->v.e * m->s.v;
    if (m->s.v < V_MIN) {
        m->s.v = 0.0;
        m->s.resting = 1;
    }
    m->s.pending = 0;
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    Grid grid;
    double t = m->time, t_next;
    *event = 0;
    *t_reached = t_end;
    if (m->s.pending) { /* an importer that skipped event mode */
        bounce(m);
    }
    grid_start(&grid, t, SOLVER_STEP, t_end);
    while (!m->s.resting && grid_next(&grid, t, &t_next)) {
        const double dt = t_next - t;
        m->s.h += dt * m->s.v;
        m->s.v += dt * m->v.g;
        t = t_next;
        if (m->s.h <= 0.0 && m->s.v < 0.0) {
            if (m->early_return_allowed && t < t_end) {
                *t_reached = t;
                *event = 1;
                if (m->event_mode_used) {
                    m->s.pending = 1;
                } else {
                    bounce(m);
                }
                return ST_OK;
            }
            bounce(m);
        }
    }
    return ST_OK;
}

Status model_event_update(ModelInstance *m, int *again) {
    if (m->s.pending) {
        bounce(m);
    }
    *again = 0;
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) {
    (void)m;
    (void)z;
}
