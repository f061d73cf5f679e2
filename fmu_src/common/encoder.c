/* Quadrature encoder with exact edge instants.
 *
 * Shared by the Servo and Conveyor plants (`shared` in their model.toml, with roots.c that it
 * uses): the build copies it and encoder.h into each FMU's sources/, so every FMU stays complete
 * on its own.
 *
 * The count is floor(position) with the position in counts: moving up, the count becomes n when
 * the position reaches n; moving down, it becomes n - 1 when the position drops below n. The
 * plant calls encoder_track for each piece of its trajectory on which the position is monotonic;
 * the instants of the last two edges are then found by root finding on the plant's own
 * continuous position, so they are exact to the root tolerance whatever the solver step. */
#include <math.h>

#include "cosim_fmu.h"

void encoder_start(Encoder *e, double position, double t) {
    e->count = (int64_t)floor(position);
    e->edge = e->count;
    e->direction = 1;
    e->t_last = t;
    e->t_prev = t;
}

/* The instant in [a, b] at which the position passes the boundary c->level. */
static double crossing_time(const Passing *c, double a, double b, double tol) {
    return root_after(passing, c, a, passing(c, a), b, passing(c, b), c->dir < 0.0, tol);
}

void encoder_track(Encoder *e, ScalarFn position, const void *ctx, double a, double b, double pb, double t_origin,
                   double tol) {
    Passing c;
    double whole = floor(pb);
    int64_t count;
    int down;
    if (!(fabs(whole) < 9.0e18)) {
        return; /* beyond the range of the counter: the plant's checks keep positions finite */
    }
    count = (int64_t)whole;
    if (count == e->count) {
        return;
    }
    down = count < e->count;
    c.f = position;
    c.ctx = ctx;
    c.dir = down ? -1.0 : 1.0;
    c.level = (double)(down ? count + 1 : count);
    e->t_prev = e->t_last;
    e->t_last = t_origin + crossing_time(&c, a, b, tol);
    if (down ? e->count - count >= 2 : count - e->count >= 2) {
        c.level = (double)(down ? count + 2 : count - 1);
        e->t_prev = t_origin + crossing_time(&c, a, b, tol);
    }
    e->edge = down ? count + 1 : count;
    e->direction = down ? -1 : 1;
    e->count = count;
}

int32_t wrap_int32(int64_t value) {
    uint32_t low = (uint32_t)((uint64_t)value & 0xffffffffu);
    return low > 0x7fffffffu ? (int32_t)((int64_t)low - 4294967296LL) : (int32_t)low;
}

void encoder_outputs(const Encoder *e, int32_t *count, int32_t *edge, int32_t *direction, double *t_last,
                     double *t_prev) {
    *count = wrap_int32(e->count);
    *edge = wrap_int32(e->edge);
    *direction = e->direction;
    *t_last = e->t_last;
    *t_prev = e->t_prev;
}
