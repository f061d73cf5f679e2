/* Dahlquist (bench model): der(x) = -k x, forward Euler on the internal grid t0 + k h (h = 0.1 s). */
#include "cosim_fmu.h"
#include "grid.h"

#define SOLVER_STEP 0.1

Status model_init(ModelInstance *m) {
    m->s.x = 1.0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) { m->v.x = m->s.x; }

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    Grid grid;
    double t = m->time, t_next;
    *event = 0;
    grid_start(&grid, t, SOLVER_STEP, t_end);
    while (grid_next(&grid, t, &t_next)) {
        m->s.x += (t_next - t) * (-m->v.k * m->s.x);
        t = t_next;
    }
    *t_reached = t_end;
    return ST_OK;
}
