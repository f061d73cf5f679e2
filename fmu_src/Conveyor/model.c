/* Conveyor: a master axis driven by a speed command, with a quadrature encoder and a
 * registration-mark sensor.
 *
 *     dv/dt = (speed_cmd - v) / tau_drive
 *     dx/dt = v + disturbance + A sin(2 pi f (t - t_start) + phi)
 *
 * With the inputs held over a communication step the solution is closed form:
 *
 *     v(t) = c + (v0 - c) e^(-t/tau)
 *     x(t) = x0 + (c + d) t + (v0 - c) tau (1 - e^(-t/tau)) + (A / w) (cos(th0) - cos(th0 + w t))
 *
 * The model walks internal steps t0 + k*h (h = min(max_step, tau/4, 1/(8 f))), cuts each at a
 * zero of the acceleration and then at a zero of the speed, so the position is monotonic on every
 * piece, and locates on each piece, by root finding on x(t), the mark edges (the sensor is on
 * while x is in [mark_offset + k*pitch, mark_offset + k*pitch + length)) and the encoder edges
 * (encoder.c). A mark edge is an event: with FMI 3.0 early return the step ends at it (and with
 * event mode the sensor output changes in event mode); otherwise the step goes on past it. */
#include <math.h>

#include "cosim_fmu.h"
#include "grid.h"

#define ROOT_TOL 1e-12 /* s: mark and encoder edges */
#define TWO_PI 6.283185307179586

/* The closed-form trajectory from one instant (origin) with the inputs of the current step. */
typedef struct {
    const ModelInstance *m;
    double x0, v0;
    double c, d;        /* speed_cmd, disturbance */
    double tau;
    double amp, omega;  /* ripple (amp = 0 without) */
    double th0;         /* ripple phase at the origin */
    double cpm;         /* counts per metre */
} Segment;

static int has_ripple(const ModelInstance *m) { return m->v.ripple_amplitude > 0.0 && m->v.ripple_frequency > 0.0; }

static double ripple_phase(const ModelInstance *m, double t) {
    return TWO_PI * m->v.ripple_frequency * (t - m->start_time) + m->v.ripple_phase;
}

static void segment_start(const ModelInstance *m, Segment *seg, double t) {
    seg->m = m;
    seg->x0 = m->s.x;
    seg->v0 = m->s.v;
    seg->c = m->v.speed_cmd;
    seg->d = m->v.disturbance;
    seg->tau = m->v.tau_drive;
    seg->amp = has_ripple(m) ? m->v.ripple_amplitude : 0.0;
    seg->omega = TWO_PI * m->v.ripple_frequency;
    seg->th0 = has_ripple(m) ? ripple_phase(m, t) : 0.0;
    seg->cpm = m->v.counts_per_metre;
}

static double seg_drive_speed(const Segment *seg, double t) {
    return seg->c + (seg->v0 - seg->c) * exp(-t / seg->tau);
}

static double seg_position(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    double x = seg->x0 + (seg->c + seg->d) * t + (seg->v0 - seg->c) * seg->tau * -expm1(-t / seg->tau);
    if (seg->amp > 0.0) {
        x += 2.0 * seg->amp / seg->omega * sin(seg->th0 + 0.5 * seg->omega * t) * sin(0.5 * seg->omega * t);
    }
    return x;
}

static double seg_speed(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    double v = seg_drive_speed(seg, t) + seg->d;
    return seg->amp > 0.0 ? v + seg->amp * sin(seg->th0 + seg->omega * t) : v;
}

static double seg_accel(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    double a = -(seg->v0 - seg->c) / seg->tau * exp(-t / seg->tau);
    return seg->amp > 0.0 ? a + seg->amp * seg->omega * cos(seg->th0 + seg->omega * t) : a;
}

static double seg_counts(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    return seg_position(seg, t) * seg->cpm;
}

/* Where the sensor state changes next: [lo, hi) is the interval of the current state. */
static void mark_bounds(const ModelInstance *m, double *lo, double *hi) {
    const double start = m->v.mark_offset + (double)m->s.mark_k * m->v.mark_pitch;
    if (m->s.mark_on) {
        *lo = start;
        *hi = start + m->v.mark_length;
    } else {
        *lo = start + m->v.mark_length;
        *hi = start + m->v.mark_pitch;
    }
}

/* The sensor passes the boundary hi (dir > 0) or lo (dir < 0) at time t. */
static void mark_edge(ModelInstance *m, int dir, double t) {
    ModelState *s = &m->s;
    int rising;
    if (dir > 0) {
        rising = !s->mark_on;
        s->mark_k += s->mark_on ? 0 : 1;
    } else {
        rising = !s->mark_on;
        s->mark_k -= s->mark_on ? 1 : 0;
    }
    s->mark_on = rising;
    if (rising) {
        s->marks_seen++;
        s->t_last_mark = t;
    }
    cf_log(m, ST_OK, "logEvents", "mark sensor %s at t = %.17g s (x = %.17g m)", rising ? "on" : "off", t, s->x);
}

static void set_state(ModelInstance *m, const Segment *seg, double t) {
    m->s.x = seg_position(seg, t);
    m->s.v = seg_drive_speed(seg, t);
}

/* Walk the monotonic piece [p, q] of a segment from t_origin: mark events and encoder edges.
 * Returns 1 if the step must end at a mark edge (early return), with the state there. */
static int walk_piece(ModelInstance *m, const Segment *seg, double p, double q, double t_origin, double *t_event) {
    ModelState *s = &m->s;
    const double xq = seg_position(seg, q);
    for (;;) {
        double lo, hi, te;
        Passing past;
        mark_bounds(m, &lo, &hi);
        past.f = seg_position;
        past.ctx = seg;
        if (xq >= hi) {
            past.dir = 1.0;
            past.level = hi;
        } else if (xq < lo) {
            past.dir = -1.0;
            past.level = lo;
        } else {
            encoder_track(&s->enc, seg_counts, seg, p, q, xq * seg->cpm, t_origin, ROOT_TOL);
            return 0;
        }
        te = root_after(passing, &past, p, passing(&past, p), q, passing(&past, q), past.dir < 0.0, ROOT_TOL);
        encoder_track(&s->enc, seg_counts, seg, p, te, seg_counts(seg, te), t_origin, ROOT_TOL);
        if (m->early_return_allowed) {
            set_state(m, seg, te);
            if (m->event_mode_used) {
                s->pending = (int)past.dir; /* applied in event mode */
            } else {
                mark_edge(m, (int)past.dir, t_origin + te);
            }
            *t_event = te;
            return 1;
        }
        s->x = seg_position(seg, te); /* for the log message only: the segment keeps its origin */
        mark_edge(m, (int)past.dir, t_origin + te);
        p = te;
    }
}

/* Advance over [0, span] from t_origin; returns 1 at an early-return event (*t_event < span). */
static int advance(ModelInstance *m, const Segment *seg, double span, double t_origin, double *t_event) {
    double cuts[4];
    int n = 0, k;
    const double acc0 = seg_accel(seg, 0.0), acc1 = seg_accel(seg, span);
    cuts[n++] = 0.0;
    if (acc0 * acc1 < 0.0) {
        cuts[n++] = root_sign_change(seg_accel, seg, 0.0, acc0, span, acc1, ROOT_TOL);
    }
    cuts[n++] = span;
    /* the speed is monotonic between the cuts: at most one zero in each */
    for (k = n - 2; k >= 0; k--) {
        const double a = cuts[k], b = cuts[k + 1];
        const double va = seg_speed(seg, a), vb = seg_speed(seg, b);
        if (va * vb < 0.0) {
            int j;
            for (j = n; j > k + 1; j--) {
                cuts[j] = cuts[j - 1];
            }
            cuts[k + 1] = root_sign_change(seg_speed, seg, a, va, b, vb, ROOT_TOL);
            n++;
        }
    }
    for (k = 0; k + 1 < n; k++) {
        if (walk_piece(m, seg, cuts[k], cuts[k + 1], t_origin, t_event)) {
            return 1;
        }
    }
    set_state(m, seg, span);
    return 0;
}

Status model_init(ModelInstance *m) {
    ModelState *s = &m->s;
    double lo, hi;
    s->h = fmin(m->v.max_step, 0.25 * m->v.tau_drive);
    if (has_ripple(m)) {
        s->h = fmin(s->h, 0.125 / m->v.ripple_frequency);
    }
    s->x = m->v.position_start;
    s->v = m->v.speed_start;
    s->mark_k = (int64_t)floor((s->x - m->v.mark_offset) / m->v.mark_pitch);
    s->mark_on = s->x - (m->v.mark_offset + (double)s->mark_k * m->v.mark_pitch) < m->v.mark_length;
    mark_bounds(m, &lo, &hi);
    if (s->x >= hi) { /* rounding at a boundary: step into the interval that holds x */
        s->mark_on = !s->mark_on;
        s->mark_k += s->mark_on ? 1 : 0;
    }
    s->pending = 0;
    s->marks_seen = 0;
    s->t_last_mark = m->time;
    encoder_start(&s->enc, s->x * m->v.counts_per_metre, m->time);
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    if (!(m->v.mark_pitch > m->v.mark_length)) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter mark_pitch = %.17g m is not allowed (allowed: > mark_length = %.17g m)", m->v.mark_pitch,
               m->v.mark_length);
        return ST_ERROR;
    }
    if (!(fabs(m->v.position_start * m->v.counts_per_metre) < 9.0e15)) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter position_start = %.17g m is not allowed (allowed: |position_start * counts_per_metre| "
               "< 9e15 counts)", m->v.position_start);
        return ST_ERROR;
    }
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    const ModelState *s = &m->s;
    double ripple = has_ripple(m) ? m->v.ripple_amplitude * sin(ripple_phase(m, m->time)) : 0.0;
    m->v.position = s->x;
    m->v.speed = s->v + m->v.disturbance + ripple;
    m->v.drive_speed = s->v;
    encoder_outputs(&s->enc, &m->v.encoder_count, &m->v.edge_count, &m->v.edge_direction, &m->v.t_last_edge,
                    &m->v.t_prev_edge);
    m->v.mark = s->mark_on;
    m->v.marks_seen = wrap_int32(s->marks_seen);
    m->v.t_last_mark = s->t_last_mark;
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    ModelState *s = &m->s;
    double t = m->time, t_b;
    Grid grid;
    Segment seg;
    *event = 0;
    *t_reached = t_end;
    if (s->pending != 0) { /* an importer that skipped event mode: apply the edge now */
        mark_edge(m, s->pending, m->time);
        s->pending = 0;
    }
    grid_start(&grid, m->time, s->h, t_end);
    while (grid_next(&grid, t, &t_b)) {
        double t_event = 0.0;
        segment_start(m, &seg, t);
        if (advance(m, &seg, t_b - t, t, &t_event)) {
            *t_reached = t + t_event;
            *event = 1;
            return ST_OK;
        }
        t = t_b;
    }
    return ST_OK;
}

Status model_event_update(ModelInstance *m, int *again) {
    if (m->s.pending != 0) {
        mark_edge(m, m->s.pending, m->time);
        m->s.pending = 0;
    }
    *again = 0;
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) {
    double lo, hi;
    mark_bounds(m, &lo, &hi);
    z[0] = hi - m->s.x; /* > 0 until the position reaches the next edge ahead */
    z[1] = m->s.x - lo; /* >= 0 until it drops below the edge behind */
}
