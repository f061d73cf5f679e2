/* Servo: a brushed DC motor behind a voltage amplifier, with an incremental quadrature encoder.
 *
 *     u  = clamp(amplifier_gain * u_cmd, -supply_voltage, +supply_voltage)
 *     L di/dt = u - R i - Ke w
 *     J dw/dt = Kt i - B w - Tc sgn(w) - T_load,     dtheta/dt = w
 *
 * With the inputs held over a communication step and the Coulomb torque constant while the rotor
 * turns one way, the equations are linear with constant input, and the model advances them with
 * their exact solution (the matrix exponential of the 2x2 system, in closed form) over internal
 * steps t0 + k*h, h = min(max_step, 0.25 / |fastest eigenvalue|). Inside each internal step the
 * instants that change the equations are located by root finding on the exact solution: the
 * speed passing zero (the Coulomb torque changes sign, or static friction holds the rotor) and,
 * while stuck, the drive torque leaving +-Tc (breakaway). Between them the angle is monotonic,
 * and the encoder edges are located on it (encoder.c). The speed is split at zeros of the
 * acceleration first, so each piece holds at most one zero of the speed. */
#include <math.h>

#include "cosim_fmu.h"
#include "grid.h"

#define ROOT_TOL 1e-12        /* s: switching instants and encoder edges */
#define MAX_SWITCHES 1000000L /* per doStep: a guard against a model that chatters */
#define TWO_PI 6.283185307179586

/* The trajectory from one instant (origin) with fixed equations: stuck, or slipping one way. */
typedef struct {
    const ModelInstance *m;
    int stuck;
    double u;          /* motor voltage [V] */
    double i0, w0, th0;
    /* slipping: y(t) = y_ss + E(t) z0, E(t) = f I + g N, N = A - mu I */
    double i_ss, w_ss;
    double z[2], nz[2], az[2], naz[2];
    double inv_z, inv_nz; /* speed components of A^-1 z0 and A^-1 N z0 */
    /* stuck: i(t) = i_inf + (i0 - i_inf) exp(-t R/L) */
    double i_inf, rate;
} Segment;

static double sign(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

static double motor_voltage(const ModelInstance *m) {
    double u = m->v.amplifier_gain * m->v.u_cmd;
    return fmax(-m->v.supply_voltage, fmin(m->v.supply_voltage, u));
}

/* f - 1 and g of E(t) = f I + g N, accurate for small t. */
static void transition(const ModelState *s, double t, double *fm1, double *g) {
    if (s->q > 1e-12 * s->mu * s->mu) {
        double e1 = expm1(s->l1 * t), e2 = expm1(s->l2 * t);
        *fm1 = 0.5 * (e1 + e2);
        *g = (e1 - e2) / (s->l1 - s->l2);
    } else if (s->q < -1e-12 * s->mu * s->mu) {
        double em = expm1(s->mu * t), half = sin(0.5 * s->nu * t);
        *fm1 = em * cos(s->nu * t) - 2.0 * half * half;
        *g = (1.0 + em) * sin(s->nu * t) / s->nu;
    } else { /* critically damped: series in q t^2 */
        double em = expm1(s->mu * t), qt2 = s->q * t * t;
        *fm1 = em + (1.0 + em) * 0.5 * qt2;
        *g = (1.0 + em) * t * (1.0 + qt2 / 6.0);
    }
}

static double drive_torque(const ModelInstance *m, double i) { return m->v.torque_constant * i - m->v.load_torque; }

static void segment_start(const ModelInstance *m, Segment *seg) {
    const ModelState *s = &m->s;
    const double b1 = seg->u / m->v.inductance;
    const double b2 = (-m->v.coulomb_friction * (double)s->dir - m->v.load_torque) / m->v.inertia;
    const double n11 = s->a11 - s->mu, n22 = s->a22 - s->mu;
    seg->m = m;
    seg->stuck = s->stuck;
    seg->i0 = s->i;
    seg->w0 = s->w;
    seg->th0 = s->theta;
    seg->i_inf = seg->u / m->v.resistance;
    seg->rate = m->v.resistance / m->v.inductance;
    seg->i_ss = -(s->a22 * b1 - s->a12 * b2) / s->det;
    seg->w_ss = -(-s->a21 * b1 + s->a11 * b2) / s->det;
    seg->z[0] = s->i - seg->i_ss;
    seg->z[1] = s->w - seg->w_ss;
    seg->nz[0] = n11 * seg->z[0] + s->a12 * seg->z[1];
    seg->nz[1] = s->a21 * seg->z[0] + n22 * seg->z[1];
    seg->az[0] = s->a11 * seg->z[0] + s->a12 * seg->z[1];
    seg->az[1] = s->a21 * seg->z[0] + s->a22 * seg->z[1];
    seg->naz[0] = n11 * seg->az[0] + s->a12 * seg->az[1];
    seg->naz[1] = s->a21 * seg->az[0] + n22 * seg->az[1];
    seg->inv_z = (-s->a21 * seg->z[0] + s->a11 * seg->z[1]) / s->det;
    seg->inv_nz = (-s->a21 * seg->nz[0] + s->a11 * seg->nz[1]) / s->det;
}

static double seg_current(const Segment *seg, double t) {
    double fm1, g;
    if (seg->stuck) {
        return seg->i0 + (seg->i_inf - seg->i0) * -expm1(-seg->rate * t);
    }
    transition(&seg->m->s, t, &fm1, &g);
    return seg->i_ss + (1.0 + fm1) * seg->z[0] + g * seg->nz[0];
}

static double seg_speed(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    double fm1, g;
    if (seg->stuck) {
        return 0.0;
    }
    transition(&seg->m->s, t, &fm1, &g);
    return seg->w_ss + (1.0 + fm1) * seg->z[1] + g * seg->nz[1];
}

static double seg_accel(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    double fm1, g;
    transition(&seg->m->s, t, &fm1, &g);
    return (1.0 + fm1) * seg->az[1] + g * seg->naz[1];
}

static double seg_angle(const Segment *seg, double t) {
    double fm1, g;
    if (seg->stuck) {
        return seg->th0;
    }
    transition(&seg->m->s, t, &fm1, &g);
    return seg->th0 + seg->w_ss * t + fm1 * seg->inv_z + g * seg->inv_nz;
}

static double seg_counts(const void *ctx, double t) {
    const Segment *seg = (const Segment *)ctx;
    return seg_angle(seg, t) * (double)seg->m->v.counts_per_rev / TWO_PI;
}

/* Static friction: beyond the breakaway torque (> 0 up, < 0 down, measured as sgn * drive - Tc). */
typedef struct {
    const Segment *seg;
    double sgn;
} Breakaway;

static double past_breakaway(const void *ctx, double t) {
    const Breakaway *b = (const Breakaway *)ctx;
    return b->sgn * drive_torque(b->seg->m, seg_current(b->seg, t)) - b->seg->m->v.coulomb_friction;
}

/* The rotor stands still (w == 0): stuck if static friction holds it, else the way it starts. */
static void decide_at_rest(ModelInstance *m) {
    ModelState *s = &m->s;
    double drive = drive_torque(m, s->i);
    s->w = 0.0;
    if (m->v.coulomb_friction > 0.0 && fabs(drive) <= m->v.coulomb_friction) {
        s->stuck = 1;
        s->dir = 0;
    } else {
        s->stuck = 0;
        s->dir = (int)sign(drive);
    }
}

static void set_state(ModelInstance *m, const Segment *seg, double t) {
    ModelState *s = &m->s;
    s->i = seg_current(seg, t);
    s->w = seg_speed(seg, t);
    s->theta = seg_angle(seg, t);
}

/* Advance over [0, span] from the segment's origin t_origin. Returns 1 if the equations change at
 * *t_switch < span (the state is then at that instant), 0 if the state is at span. */
static int advance(ModelInstance *m, const Segment *seg, double span, double t_origin, double *t_switch) {
    ModelState *s = &m->s;
    const double tc = m->v.coulomb_friction;
    double cuts[3];
    int n = 0, k;
    if (seg->stuck) {
        double drive = drive_torque(m, seg_current(seg, span));
        if (fabs(drive) > tc) {
            Breakaway b;
            b.seg = seg;
            b.sgn = sign(drive);
            *t_switch = root_after(past_breakaway, &b, 0.0, past_breakaway(&b, 0.0), span,
                                   past_breakaway(&b, span), 1, ROOT_TOL);
            s->i = seg_current(seg, *t_switch);
            s->stuck = 0;
            s->dir = (int)b.sgn;
            return 1;
        }
        s->i = seg_current(seg, span);
        return 0;
    }
    /* pieces on which the speed is monotonic: cut at a zero of the acceleration */
    cuts[n++] = 0.0;
    {
        double acc0 = seg_accel(seg, 0.0), acc1 = seg_accel(seg, span);
        if (acc0 * acc1 < 0.0) {
            cuts[n++] = root_sign_change(seg_accel, seg, 0.0, acc0, span, acc1, ROOT_TOL);
        }
    }
    cuts[n++] = span;
    for (k = 0; k + 1 < n; k++) {
        const double p = cuts[k], q = cuts[k + 1];
        const double wq = seg_speed(seg, q);
        if (s->dir == 0 && tc == 0.0) {
            s->dir = (int)sign(wq); /* without Coulomb friction the direction is only a label */
        }
        if ((double)s->dir * wq < 0.0) {
            const double tz = root_sign_change(seg_speed, seg, p, seg_speed(seg, p), q, wq, ROOT_TOL);
            encoder_track(&s->enc, seg_counts, seg, p, tz, seg_counts(seg, tz), t_origin, ROOT_TOL);
            set_state(m, seg, tz);
            decide_at_rest(m);
            if (!s->stuck && s->dir == 0) {
                s->dir = -(int)sign(wq); /* no friction and no drive: keeps turning the new way */
            }
            *t_switch = tz;
            return 1;
        }
        encoder_track(&s->enc, seg_counts, seg, p, q, seg_counts(seg, q), t_origin, ROOT_TOL);
    }
    set_state(m, seg, span);
    return 0;
}

Status model_init(ModelInstance *m) {
    ModelState *s = &m->s;
    const double R = m->v.resistance, L = m->v.inductance, J = m->v.inertia;
    double rho;
    s->a11 = -R / L;
    s->a12 = -m->v.back_emf_constant / L;
    s->a21 = m->v.torque_constant / J;
    s->a22 = -m->v.viscous_friction / J;
    s->det = s->a11 * s->a22 - s->a12 * s->a21;
    s->mu = 0.5 * (s->a11 + s->a22);
    s->q = s->mu * s->mu - s->det;
    if (s->q > 0.0) {
        s->l1 = s->mu + sqrt(s->q);
        s->l2 = s->mu - sqrt(s->q);
        s->nu = 0.0;
        rho = fabs(s->l2);
    } else {
        s->l1 = s->l2 = s->mu;
        s->nu = sqrt(-s->q);
        rho = sqrt(s->det);
    }
    s->h = fmin(m->v.max_step, 0.25 / rho);
    s->i = 0.0;
    s->theta = m->v.angle_start;
    decide_at_rest(m);
    encoder_start(&s->enc, s->theta * (double)m->v.counts_per_rev / TWO_PI, m->time);
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    const double kt = m->v.torque_constant, ke = m->v.back_emf_constant;
    if (m->v.counts_per_rev % 4 != 0) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter counts_per_rev = %d is not allowed (allowed: a positive multiple of 4, "
               "the quadrature counts of a whole number of encoder lines)",
               (int)m->v.counts_per_rev);
        return ST_ERROR;
    }
    if (fabs(kt - ke) > 0.1 * fmax(kt, ke)) {
        cf_log(m, ST_WARNING, "logStatusWarning",
               "torque_constant = %g N.m/A and back_emf_constant = %g V.s/rad differ by more than 10 %% "
               "(in SI units they are equal for an ideal DC motor): check the units of the datasheet values",
               kt, ke);
    }
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    const ModelState *s = &m->s;
    m->v.angle = s->theta;
    m->v.speed = s->w;
    m->v.current = s->i;
    m->v.motor_voltage = motor_voltage(m);
    m->v.torque = m->v.torque_constant * s->i;
    m->v.stuck = s->stuck;
    encoder_outputs(&s->enc, &m->v.encoder_count, &m->v.edge_count, &m->v.edge_direction, &m->v.t_last_edge,
                    &m->v.t_prev_edge);
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    ModelState *s = &m->s;
    double t = m->time, t_b;
    long switches = 0;
    Grid grid;
    Segment seg;
    *event = 0;
    *t_reached = t_end;
    seg.u = motor_voltage(m);
    grid_start(&grid, m->time, s->h, t_end);
    while (grid_next(&grid, t, &t_b)) {
        double t_switch = 0.0;
        if (s->stuck || s->w == 0.0) {
            if (!s->stuck || fabs(drive_torque(m, s->i)) > m->v.coulomb_friction) {
                decide_at_rest(m); /* an input changed, or the rotor starts from rest */
            }
        }
        segment_start(m, &seg);
        if (advance(m, &seg, t_b - t, t, &t_switch)) {
            t += t_switch;
            if (++switches > MAX_SWITCHES) {
                cf_log(m, ST_ERROR, "logStatusError", "doStep: more than %ld friction switches in one step at t = %.17g s",
                       MAX_SWITCHES, t);
                return ST_ERROR;
            }
            continue;
        }
        t = t_b;
    }
    return ST_OK;
}
