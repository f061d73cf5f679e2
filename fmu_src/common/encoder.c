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

typedef struct {
    ScalarFn position;
    const void *ctx;
    double boundary;
    int down;
} Crossing;

/* > 0 (or >= 0 moving up) once the position has crossed the boundary. */
static double past_boundary(const void *ctx, double t) {
    const Crossing *c = (const Crossing *)ctx;
    double p = c->position(c->ctx, t);
    return c->down ? c->boundary - p : p - c->boundary;
}

static double crossing_time(const Crossing *c, double a, double b, double tol) {
    double ga = past_boundary(c, a), gb = past_boundary(c, b);
    return root_after(past_boundary, c, a, ga, b, gb, c->down, tol);
}

void encoder_track(Encoder *e, ScalarFn position, const void *ctx, double a, double b, double pb, double t_origin,
                   double tol) {
    Crossing c;
    double whole = floor(pb);
    int64_t count;
    if (!(fabs(whole) < 9.0e18)) {
        return; /* beyond the range of the counter: the plant's checks keep positions finite */
    }
    count = (int64_t)whole;
    if (count == e->count) {
        return;
    }
    c.position = position;
    c.ctx = ctx;
    c.down = count < e->count;
    c.boundary = (double)(c.down ? count + 1 : count);
    e->t_prev = e->t_last;
    e->t_last = t_origin + crossing_time(&c, a, b, tol);
    if (c.down ? e->count - count >= 2 : count - e->count >= 2) {
        c.boundary = (double)(c.down ? count + 2 : count - 1);
        e->t_prev = t_origin + crossing_time(&c, a, b, tol);
    }
    e->edge = c.down ? count + 1 : count;
    e->direction = c.down ? -1 : 1;
    e->count = count;
}

int32_t wrap_int32(int64_t value) {
    uint32_t low = (uint32_t)((uint64_t)value & 0xffffffffu);
    return low > 0x7fffffffu ? (int32_t)((int64_t)low - 4294967296LL) : (int32_t)low;
}
