/* Stepper: a two-phase hybrid stepper motor with its microstepping driver.
 *
 * Motor (Nr = steps_per_rev / 4 rotor teeth, theta = rotor angle):
 *
 *     T = -Kt ia sin(Nr theta) + Kt ib cos(Nr theta) - Td sin(4 Nr theta)
 *     J dw/dt = T - B w - T_load - T_friction,   J = J_rotor + J_load + m (lead / 2 pi)^2
 *
 * Driver: step pulse n moves the commanded electrical angle to n * (pi/2) / microsteps and the
 * commanded phase currents to I cos, I sin of it. With phase_inductance = 0 the currents follow at
 * once (ideal current source); otherwise each phase obeys L di/dt = v - R i - e with the voltage
 * v = clamp(R i + e + L (i_cmd - i) / current_tau, -V, V) of a current loop whose bus voltage
 * limits it (back-EMF e_a = -Kt w sin(Nr theta), e_b = Kt w cos(Nr theta)).
 *
 * Pulses: step_rate (signed) and step_phase are applied at the start of the first step after
 * either changed; pulse j of that anchor is at t_anchor + (j - step_phase) / |step_rate|, for
 * j = 0, 1, ... not before t_anchor. A step covers [t_start, t_end): a pulse at t_end belongs to the
 * next step. Pulse instants derive from the pulse index j, never from a sum of periods.
 *
 * Integration: classic Runge-Kutta 4 for the rotor between pulses, on equal sub-steps
 * (t = a + (b - a) i / n) no longer than the bound of step_bound(). With L > 0 each rotor sub-step
 * integrates the two phase currents first, by RK4 on finer sub-steps of at most current_tau / 4
 * with the back-EMF linear in time over the rotor sub-step (from the state at its start and its
 * derivative); the rotor's stages take the currents at the middle and the end. Switch crossings
 * are located by the shared root finder (root_after, roots.c: regula falsi, Illinois, with
 * bisection) to a bracket narrower than EVENT_TOL; with FMI 3.0 early return the step stops just
 * after the crossing, otherwise the step goes on. */
#include <math.h>
#include <stdint.h>

#include "cosim_fmu.h"
#include "roots.h"

#define TWO_PI 6.283185307179586
#define PULSE_EPS 1e-11  /* [s] a pulse this close to a step boundary lies on it */
#define EVENT_TOL 1e-11  /* [s] width of the bracket around a located switch crossing */
#define CHUNK 1e-3       /* [s] the sub-step size is chosen afresh at least this often */
#define N_SWITCHES 3

/* Everything the derivative needs, fixed over one pulse interval. */
typedef struct {
    double nr, kt, td, inertia, damping, friction, load;
    double ia_cmd, ib_cmd;
    int ideal; /* currents equal the commanded ones */
    double inductance, resistance, voltage, tau;
    double loop_gain;      /* L / current_tau [ohm] */
    double inv_inductance; /* 1 / L [1/H] (0 with an ideal source) */
    double h_fixed;        /* [s] the sub-step bound that does not depend on speed (see step_bound) */
    double electrical_per_step; /* [rad] electrical angle of one microstep */
} Dynamics;

static int rotor_teeth(const ModelInstance *m) { return m->v.steps_per_rev / 4; }

static double total_inertia(const ModelInstance *m) {
    double r = m->v.screw_lead / TWO_PI;
    return m->v.rotor_inertia + m->v.load_inertia + m->v.carriage_mass * r * r;
}

/* Commanded electrical angle [rad] after `steps` microsteps (exact modulo one electrical turn). */
static double electrical_angle(const ModelInstance *m, int64_t steps) {
    const int64_t turn = 4 * (int64_t)m->v.microsteps;
    int64_t k = steps % turn;
    if (k < 0) {
        k += turn;
    }
    return (double)k * (TWO_PI / (double)turn);
}

static void commanded_currents(const ModelInstance *m, double *ia, double *ib) {
    const double amplitude = m->v.enable ? m->v.current : 0.0;
    const double angle = electrical_angle(m, m->s.steps);
    *ia = amplitude * cos(angle);
    *ib = amplitude * sin(angle);
}

/* Everything of Dynamics but the commanded currents: fixed over a whole doStep. */
static void dynamics(const ModelInstance *m, Dynamics *d) {
    double stiffness;
    d->nr = (double)rotor_teeth(m);
    d->kt = m->v.torque_constant;
    d->td = m->v.detent_torque;
    d->inertia = total_inertia(m);
    d->damping = m->v.viscous_damping;
    d->friction = m->v.friction_torque;
    d->load = m->v.load_torque;
    commanded_currents(m, &d->ia_cmd, &d->ib_cmd);
    d->ideal = !(m->v.phase_inductance > 0.0);
    d->inductance = m->v.phase_inductance;
    d->resistance = m->v.phase_resistance;
    d->voltage = m->v.supply_voltage;
    d->tau = m->v.current_tau;
    d->loop_gain = d->ideal ? 0.0 : d->inductance / d->tau;
    d->inv_inductance = d->ideal ? 0.0 : 1.0 / d->inductance;
    /* max_step and 1/50 of the small-signal natural period (the current loop has its own sub-steps) */
    d->h_fixed = m->v.max_step;
    stiffness = d->nr * (d->kt * m->v.current + 4.0 * d->td);
    if (stiffness > 0.0) {
        d->h_fixed = fmin(d->h_fixed, TWO_PI / sqrt(stiffness / d->inertia) / 50.0);
    }
    d->electrical_per_step = TWO_PI / (4.0 * (double)m->v.microsteps);
}

static double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* Motor torque from s = sin(Nr theta), c = cos(Nr theta); sin(4 Nr theta) = 4 s c (c^2 - s^2). */
static double torque_sc(const Dynamics *d, double ia, double ib, double s, double c) {
    return d->kt * (ib * c - ia * s) - d->td * 4.0 * s * c * (c * c - s * s);
}

static double motor_torque(const Dynamics *d, const MotorState *x) {
    const double e = d->nr * x->theta;
    return torque_sc(d, x->ia, x->ib, sin(e), cos(e));
}

/* Torque on the shaft except Coulomb friction. */
static double drive_torque(const Dynamics *d, const MotorState *x) {
    return motor_torque(d, x) - d->damping * x->omega - d->load;
}

/* Coulomb friction: +-Tc while moving; at rest it holds up to Tc (stick). */
static double friction_torque(const Dynamics *d, double omega, double drive) {
    if (!(d->friction > 0.0)) {
        return 0.0;
    }
    if (omega > 0.0) {
        return d->friction;
    }
    if (omega < 0.0) {
        return -d->friction;
    }
    return clamp(drive, -d->friction, d->friction);
}

/* Rotor acceleration [rad/s^2] at angle theta and speed omega with the phase currents ia, ib,
 * from s = sin(Nr theta), c = cos(Nr theta). */
static double acceleration(const Dynamics *d, double omega, double ia, double ib, double s, double c) {
    const double drive = torque_sc(d, ia, ib, s, c) - d->damping * omega - d->load;
    return (drive - friction_torque(d, omega, drive)) / d->inertia;
}

/* The current loop's voltage demand R i + e + L (i_cmd - i) / current_tau (before the bus clamp). */
static double demand(const Dynamics *d, double i, double i_cmd, double e) {
    return d->resistance * i + e + d->loop_gain * (i_cmd - i);
}

/* di/dt of one phase with back-EMF e and commanded current i_cmd: the current loop's voltage,
 * clamped to the bus, drives L di/dt = v - R i - e. */
static double current_slope(const Dynamics *d, double i, double i_cmd, double e) {
    const double v = clamp(demand(d, i, i_cmd, e), -d->voltage, d->voltage);
    return (v - d->resistance * i - e) * d->inv_inductance;
}

/* Both phase currents over [0, h] with the back-EMFs taken linear in time, e(t) = e0 + de t, on n
 * (even) equal sub-steps of at most current_tau / 4. A sub-step on which the loop's voltage stays
 * within the bus at both ends is the loop's exact solution, i_cmd + (i - i_cmd) exp(-t / tau)
 * (no back-EMF in it); one on which it saturates is RK4. Returns the currents at h / 2 and at h. */
static void currents(const Dynamics *d, const double i0[2], const double i_cmd[2], const double e0[2],
                     const double de[2], double h, double mid[2], double end[2]) {
    const long half = (long)ceil(h / (0.5 * d->tau) - 1e-9) > 1 ? (long)ceil(h / (0.5 * d->tau) - 1e-9) : 1;
    const long n = 2 * half;
    const double hc = h / (double)n, decay = exp(-hc / d->tau);
    int p;
    for (p = 0; p < 2; p++) {
        double i = i0[p];
        long k;
        for (k = 0; k < n; k++) {
            const double t0 = hc * (double)k, ea = e0[p] + de[p] * t0, eb = e0[p] + de[p] * (t0 + hc);
            const double tracked = i_cmd[p] + (i - i_cmd[p]) * decay;
            if (fabs(demand(d, i, i_cmd[p], ea)) <= d->voltage && fabs(demand(d, tracked, i_cmd[p], eb)) <= d->voltage) {
                i = tracked;
            } else {
                const double em = e0[p] + de[p] * (t0 + 0.5 * hc);
                const double k1 = current_slope(d, i, i_cmd[p], ea);
                const double k2 = current_slope(d, i + 0.5 * hc * k1, i_cmd[p], em);
                const double k3 = current_slope(d, i + 0.5 * hc * k2, i_cmd[p], em);
                const double k4 = current_slope(d, i + hc * k3, i_cmd[p], eb);
                i += hc / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
            if (k + 1 == half) {
                mid[p] = i;
            }
        }
        end[p] = i;
    }
}

/* One step of size h from x0: RK4 for the rotor; the currents (when L > 0) follow their loop
 * over the step on finer sub-steps (currents()), with the back-EMF linearised from x0 and its
 * rate of change. Then the stick check of Coulomb friction. */
static void rk4(const Dynamics *d, const MotorState *x0, double h, MotorState *x1) {
    double s = sin(d->nr * x0->theta), c = cos(d->nr * x0->theta);
    double ia_m = x0->ia, ib_m = x0->ib, ia_e = x0->ia, ib_e = x0->ib;
    double w1, a1, w2, a2, w3, a3, w4, a4, th;
    w1 = x0->omega;
    a1 = acceleration(d, w1, x0->ia, x0->ib, s, c);
    if (!d->ideal) {
        const double i0[2] = {x0->ia, x0->ib}, i_cmd[2] = {d->ia_cmd, d->ib_cmd};
        const double ws = d->kt * x0->omega;
        const double e0[2] = {-ws * s, ws * c};
        const double spin = d->nr * x0->omega * x0->omega;
        const double de[2] = {-d->kt * (a1 * s + spin * c), d->kt * (a1 * c - spin * s)};
        double mid[2], end[2];
        currents(d, i0, i_cmd, e0, de, h, mid, end);
        ia_m = mid[0];
        ib_m = mid[1];
        ia_e = end[0];
        ib_e = end[1];
    }
    th = x0->theta + 0.5 * h * w1;
    w2 = x0->omega + 0.5 * h * a1;
    s = sin(d->nr * th);
    c = cos(d->nr * th);
    a2 = acceleration(d, w2, ia_m, ib_m, s, c);
    th = x0->theta + 0.5 * h * w2;
    w3 = x0->omega + 0.5 * h * a2;
    s = sin(d->nr * th);
    c = cos(d->nr * th);
    a3 = acceleration(d, w3, ia_m, ib_m, s, c);
    th = x0->theta + h * w3;
    w4 = x0->omega + h * a3;
    s = sin(d->nr * th);
    c = cos(d->nr * th);
    a4 = acceleration(d, w4, ia_e, ib_e, s, c);
    x1->theta = x0->theta + h / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
    x1->omega = x0->omega + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    x1->ia = ia_e;
    x1->ib = ib_e;
    if (d->friction > 0.0 && x0->omega != 0.0) {
        /* The rotor comes to rest inside this step if its deceleration at the start stops it within
         * h (RK4 stages on both sides of the friction discontinuity would otherwise leave a small
         * spurious speed). It then stays at rest if friction can hold it. */
        const double a0 = a1;
        MotorState rest = *x1;
        rest.omega = 0.0;
        if ((x0->omega * a0 < 0.0 && fabs(x0->omega) <= fabs(a0) * h) || x0->omega * x1->omega < 0.0) {
            if (fabs(drive_torque(d, &rest)) <= d->friction) {
                x1->theta = x0->theta + (x0->omega * a0 < 0.0 ? 0.5 * x0->omega * fabs(x0->omega / a0)
                                                                : 0.5 * x0->omega * h);
                x1->omega = 0.0;
            }
        }
    }
}

/* Largest sub-step [s]: max_step, 1/50 of the small-signal natural period (Dynamics.h_fixed), and
 * 0.25 rad of electrical angle at the faster of the rotor's speed and the commanded speed. */
static double step_bound(const ModelInstance *m, const Dynamics *d, double omega) {
    const double electrical_speed = fmax(d->nr * fabs(omega), fabs(m->s.rate) * d->electrical_per_step);
    return electrical_speed > 0.0 ? fmin(d->h_fixed, 0.25 / electrical_speed) : d->h_fixed;
}

static double carriage_position(const ModelInstance *m, double theta) {
    return m->v.carriage_start + theta * m->v.screw_lead / TWO_PI;
}

/* Switch indicators: >= 0 while tripped (limit_pos, limit_neg, home). */
static void switch_indicators(const ModelInstance *m, double theta, double *z) {
    const double x = carriage_position(m, theta);
    z[0] = x - m->v.limit_pos_position;
    z[1] = m->v.limit_neg_position - x;
    z[2] = m->v.home_at_positive_end ? x - m->v.home_position : m->v.home_position - x;
}

/* A switch indicator over one sub-step from x0, signed so that it has crossed once > 0 (or >= 0). */
typedef struct {
    const ModelInstance *m;
    const Dynamics *d;
    const MotorState *x0;
    int k;       /* which switch */
    double sign; /* +1: z_k rises through 0 (tripped at >= 0), -1: it falls below 0 */
} Crossing;

static double crossing_value(const void *ctx, double s) {
    const Crossing *c = (const Crossing *)ctx;
    double z[N_SWITCHES];
    MotorState x;
    rk4(c->d, c->x0, s, &x);
    switch_indicators(c->m, x.theta, z);
    return c->sign * z[c->k];
}

/* Time s in (0, h] just after switch k's crossing in the sub-step x0 -> rk4(x0, h), where the
 * indicator is z0 at the start and z1 (on the other side of 0) at the end. */
static double locate_crossing(const ModelInstance *m, const Dynamics *d, const MotorState *x0, double h, int k,
                              double z0, double z1) {
    Crossing c;
    c.m = m;
    c.d = d;
    c.x0 = x0;
    c.k = k;
    c.sign = z1 >= 0.0 ? 1.0 : -1.0;
    return root_after(crossing_value, &c, 0.0, c.sign * z0, h, c.sign * z1, c.sign < 0.0, EVENT_TOL);
}

/* Integrate from a to b (no pulse in between). With stop_at_events, stop just after the first
 * switch crossing: returns 1 and its time in *t_stop. */
static int integrate(ModelInstance *m, const Dynamics *d, double a, double b, int stop_at_events, double *t_stop) {
    const double span = b - a;
    const long chunks = (long)ceil(span / CHUNK - 1e-9) > 1 ? (long)ceil(span / CHUNK - 1e-9) : 1;
    long c, i;
    for (c = 0; c < chunks; c++) {
        const double ca = a + span * (double)c / (double)chunks;
        const double cb = c + 1 == chunks ? b : a + span * (double)(c + 1) / (double)chunks;
        const double h = step_bound(m, d, m->s.x.omega);
        const long n = (long)ceil((cb - ca) / h - 1e-9) > 1 ? (long)ceil((cb - ca) / h - 1e-9) : 1;
        for (i = 0; i < n; i++) {
            const double t0 = ca + (cb - ca) * (double)i / (double)n;
            const double t1 = i + 1 == n ? cb : ca + (cb - ca) * (double)(i + 1) / (double)n;
            MotorState x1;
            rk4(d, &m->s.x, t1 - t0, &x1);
            if (stop_at_events) {
                double z0[N_SWITCHES], z1[N_SWITCHES], first = -1.0;
                int k;
                switch_indicators(m, m->s.x.theta, z0);
                switch_indicators(m, x1.theta, z1);
                for (k = 0; k < N_SWITCHES; k++) {
                    if ((z0[k] >= 0.0) != (z1[k] >= 0.0)) {
                        const double s = locate_crossing(m, d, &m->s.x, t1 - t0, k, z0[k], z1[k]);
                        if (first < 0.0 || s < first) {
                            first = s;
                        }
                    }
                }
                if (first >= 0.0) {
                    MotorState xe;
                    rk4(d, &m->s.x, first, &xe);
                    m->s.x = xe;
                    *t_stop = t0 + first;
                    return 1;
                }
            }
            m->s.x = x1;
        }
    }
    return 0;
}

static double pulse_time(const ModelState *s, int64_t j) {
    return s->t_anchor + ((double)j - s->phase) / fabs(s->rate);
}

/* Apply step_rate / step_phase at t if either changed since the last anchor. */
static void latch_pulse_train(ModelInstance *m, double t) {
    ModelState *s = &m->s;
    double first;
    if (s->anchored && s->rate == m->v.step_rate && s->phase == m->v.step_phase) {
        return;
    }
    s->anchored = 1;
    s->rate = m->v.step_rate;
    s->phase = m->v.step_phase;
    s->t_anchor = t;
    /* the first pulse not before t: j >= phase (a pulse within PULSE_EPS of t counts as at t) */
    first = s->rate != 0.0 ? ceil(s->phase - PULSE_EPS * fabs(s->rate)) : 0.0;
    s->next_pulse = first > 0.0 ? (int64_t)first : 0;
}

static int check_phase(ModelInstance *m) {
    if (!(m->v.step_phase < 1.0)) {
        cf_log(m, ST_ERROR, "logStatusError", "input step_phase = %.17g is not allowed (allowed: >= 0 and < 1)",
               m->v.step_phase);
        return 0;
    }
    return 1;
}

Status model_init(ModelInstance *m) {
    ModelState *s = &m->s;
    s->x.theta = 0.0;
    s->x.omega = 0.0;
    s->steps = 0;
    commanded_currents(m, &s->x.ia, &s->x.ib); /* the driver was on before the start */
    s->anchored = 0;
    s->rate = 0.0;
    s->phase = 0.0;
    s->t_anchor = m->time;
    s->next_pulse = 0;
    s->last_pulse_time = -1.0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    const int32_t mu = m->v.microsteps;
    if (mu < 1 || mu > 256 || (mu & (mu - 1)) != 0) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter microsteps = %d is not allowed (allowed: 1, 2, 4, 8, 16, 32, 64, 128, 256)", (int)mu);
        return ST_ERROR;
    }
    if (m->v.steps_per_rev % 4 != 0) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter steps_per_rev = %d is not allowed (allowed: a positive multiple of 4, e.g. 200 for 1.8 deg)",
               (int)m->v.steps_per_rev);
        return ST_ERROR;
    }
    if (!(m->v.limit_neg_position < m->v.limit_pos_position)) {
        cf_log(m, ST_ERROR, "logStatusError",
               "parameter limit_neg_position = %.17g m is not allowed (allowed: < limit_pos_position = %.17g m)",
               m->v.limit_neg_position, m->v.limit_pos_position);
        return ST_ERROR;
    }
    return check_phase(m) ? ST_OK : ST_ERROR;
}

void model_outputs(ModelInstance *m) {
    const ModelState *s = &m->s;
    const double nr = (double)rotor_teeth(m), mu = (double)m->v.microsteps;
    const double lead = m->v.screw_lead / TWO_PI;
    double z[N_SWITCHES], error, full, ia, ib;
    MotorState x = s->x;
    Dynamics d;
    dynamics(m, &d);
    if (d.ideal) {
        commanded_currents(m, &ia, &ib);
        x.ia = ia;
        x.ib = ib;
    }
    m->v.commanded_steps = s->steps > INT32_MAX ? INT32_MAX : (s->steps < INT32_MIN ? INT32_MIN : (int32_t)s->steps);
    m->v.angle = x.theta;
    m->v.speed = x.omega;
    m->v.carriage_position = carriage_position(m, x.theta);
    m->v.carriage_speed = x.omega * lead;
    error = (double)s->steps - x.theta * 4.0 * nr * mu / TWO_PI;
    m->v.position_error = error;
    full = fmin(fabs(error) / mu, 2.0e9); /* full steps (a tooth pitch is 4), kept in the Int32 range */
    m->v.lost_full_steps = full > 2.0 ? (int32_t)(4.0 * (floor((full - 2.0) / 4.0) + 1.0)) : 0;
    if (error < 0.0) {
        m->v.lost_full_steps = -m->v.lost_full_steps;
    }
    m->v.lost_steps = m->v.lost_full_steps != 0;
    switch_indicators(m, x.theta, z);
    m->v.limit_pos = z[0] >= 0.0;
    m->v.limit_neg = z[1] >= 0.0;
    m->v.home = z[2] >= 0.0;
    m->v.torque = motor_torque(&d, &x);
    m->v.current_a = x.ia;
    m->v.current_b = x.ib;
    m->v.last_pulse_time = s->last_pulse_time;
    if (!s->anchored || s->rate != m->v.step_rate || s->phase != m->v.step_phase || s->rate == 0.0) {
        m->v.pulse_phase = m->v.step_phase; /* these inputs take effect at this instant */
    } else {
        const double r = fabs(s->rate);
        double p = 1.0 - (pulse_time(s, s->next_pulse) - m->time) * r;
        if (p >= 1.0 - PULSE_EPS * r) {
            p = 0.0; /* a pulse is due now */
        }
        m->v.pulse_phase = clamp(p, 0.0, nextafter(1.0, 0.0));
    }
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    ModelState *s = &m->s;
    double t = m->time;
    Dynamics d;
    *event = 0;
    *t_reached = t_end;
    if (!(t_end > t)) {
        return ST_OK;
    }
    if (!check_phase(m)) {
        return ST_ERROR;
    }
    latch_pulse_train(m, t);
    dynamics(m, &d);
    for (;;) {
        const int direction = s->rate > 0.0 ? 1 : -1;
        double next = t_end, t_stop = t_end;
        /* the pulses due now: within PULSE_EPS of t, and not at the step's end */
        while (s->rate != 0.0) {
            const double tp = pulse_time(s, s->next_pulse);
            if (tp > t + PULSE_EPS || tp >= t_end - PULSE_EPS) {
                if (tp < t_end - PULSE_EPS) {
                    next = tp;
                }
                break;
            }
            if (m->v.enable) {
                s->steps += direction;
                s->last_pulse_time = tp;
            }
            s->next_pulse++;
        }
        commanded_currents(m, &d.ia_cmd, &d.ib_cmd);
        if (d.ideal) {
            s->x.ia = d.ia_cmd;
            s->x.ib = d.ib_cmd;
        }
        if (integrate(m, &d, t, next, m->early_return_allowed, &t_stop)) {
            *t_reached = t_stop;
            *event = 1;
            return ST_OK;
        }
        if (!isfinite(s->x.theta) || !isfinite(s->x.omega)) {
            cf_log(m, ST_ERROR, "logStatusError", "the solution diverged at t = %.17g s (max_step = %g s)", next,
                   m->v.max_step);
            return ST_ERROR;
        }
        t = next;
        if (t >= t_end) {
            return ST_OK;
        }
    }
}

Status model_event_update(ModelInstance *m, int *again) {
    (void)m; /* the switch outputs follow the carriage position: nothing to latch */
    *again = 0;
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) { switch_indicators(m, m->s.x.theta, z); }
