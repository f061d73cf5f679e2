/* VanDerPol (bench model): der(x0) = x1, der(x1) = mu ((1 - x0^2) x1) - x0, forward Euler on the
 * internal grid t0 + k h (h = 1e-2 s), the last step capped at the communication point. */
#include "cosim_fmu.h"
#include "grid.h"

#define SOLVER_STEP 1e-2

Status model_init(ModelInstance *m) {
    m->s.x0 = 2.0;
    m->s.x1 = 0.0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    m->v.x0 = m->s.x0;
    m->v.x1 = m->s.x1;
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    Grid grid;
    double t = m->time, t_next;
    *event = 0;
    grid_start(&grid, t, SOLVER_STEP, t_end);
    while (grid_next(&grid, t, &t_next)) {
        const double dt = t_next - t, x0 = m->s.x0, x1 = m->s.x1;
        m->s.x0 = x0 + dt * x1;
        m->s.x1 = x1 + dt * (m->v.mu * ((1.0 - x0 * x0) * x1) - x0);
        t = t_next;
    }
    *t_reached = t_end;
    return ST_OK;
}
