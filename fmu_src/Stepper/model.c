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
 * limits it (back-EMF e_a = -Kt w sin(Nr theta), e_b = Kt w cos(Nr theta)). The equations and
 * their solvers are in motor.c; this file holds the pulses, the FMI hooks and the outputs.
 *
 * Pulses come from two sources, added:
 *  - the rate train: step_rate (signed) and step_phase are applied at the start of the first step
 *    after either changed; pulse j of that anchor is at t_anchor + (j - step_phase) / |step_rate|,
 *    for j = 0, 1, ... not before t_anchor;
 *  - the segments (FMI 3.0: the array input step_segments, one row per segment: start [s],
 *    duration [s], signed pulses n): pulse k of a row is at start + k duration / |n|, k = 0 .. |n|-1.
 *    The rows are a value, not a queue: each step places the pulses of its rows that fall in it, so
 *    an importer may set the rows ahead of time and step the FMU only when it needs an output.
 * A step covers [t_start, t_end): a pulse at t_end belongs to the next step. Pulse instants derive
 * from the pulse index, never from a sum of periods. */
#include <math.h>
#include <stdint.h>

#include "cosim_fmu.h"

#define PULSE_EPS 1e-11  /* [s] a pulse this close to a step boundary lies on it */
#define SEGMENT_ROWS (N_STEP_SEGMENTS / 3)
#define MAX_SEGMENT_PULSES 1e9

static int rotor_teeth(const ModelInstance *m) { return m->v.steps_per_rev / 4; }

static double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* -- the rate train ------------------------------------------------------------------------- */
static double pulse_time(const ModelState *s, int64_t j) {
    return s->t_anchor + ((double)j - s->phase) / fabs(s->rate);
}

/* Apply step_rate / step_phase at t if either changed since the last anchor; 1 if they did. */
static int latch_pulse_train(ModelInstance *m, double t) {
    ModelState *s = &m->s;
    double first;
    if (s->anchored && s->rate == m->v.step_rate && s->phase == m->v.step_phase) {
        return 0;
    }
    s->anchored = 1;
    s->rate = m->v.step_rate;
    s->phase = m->v.step_phase;
    s->t_anchor = t;
    /* the first pulse not before t: j >= phase (a pulse within PULSE_EPS of t counts as at t) */
    first = s->rate != 0.0 ? ceil(s->phase - PULSE_EPS * fabs(s->rate)) : 0.0;
    s->next_pulse = first > 0.0 ? (int64_t)first : 0;
    return 1;
}

/* Did an input the motor's equations take change since the last step? (Then the pulse update's grid
 * restarts at this step's start.) Remembers the current values. */
static int inputs_changed(ModelInstance *m) {
    ModelState *s = &m->s;
    const int changed = s->last_enable != m->v.enable || s->last_load_torque != m->v.load_torque ||
                        s->last_current != m->v.current;
    s->last_enable = m->v.enable;
    s->last_load_torque = m->v.load_torque;
    s->last_current = m->v.current;
    return changed;
}

static int check_phase(ModelInstance *m) {
    if (!(m->v.step_phase < 1.0)) {
        cf_log(m, ST_ERROR, "logStatusError", "input step_phase = %.17g is not allowed (allowed: >= 0 and < 1)",
               m->v.step_phase);
        return 0;
    }
    return 1;
}

/* -- the segments ---------------------------------------------------------------------------- */
/* The next pulse of the segments: pulse k of row `row` (n pulses of sign `sign` from `start`). */
typedef struct {
    int row;
    int64_t k, n;
    double start, duration, rate; /* rate = n / duration [1/s] */
    int sign;
} Cursor;

static double segment_time(const Cursor *c, int64_t k) { return c->start + (double)k * c->duration / (double)c->n; }

static double segment_pulse_time(const Cursor *c) { return segment_time(c, c->k); }

/* Rows with pulses: a finite start, a duration > 0, a whole number of pulses, in time order
 * without overlap (a row may start where the previous one ends). */
static int check_segments(ModelInstance *m) {
    double end = -INFINITY;
    int r;
    for (r = 0; r < SEGMENT_ROWS; r++) {
        const double *row = &m->v.step_segments[3 * r];
        if (row[2] == 0.0) {
            continue;
        }
        if (!isfinite(row[0]) || !(row[1] > 0.0) || !isfinite(row[1]) || row[2] != floor(row[2]) ||
            !(fabs(row[2]) <= MAX_SEGMENT_PULSES)) {
            cf_log(m, ST_ERROR, "logStatusError", "input step_segments row %d = (%.17g s, %.17g s, %.17g) is not "
                   "allowed (allowed: a finite start, a duration > 0 s, a whole number of pulses up to 1e9)",
                   r, row[0], row[1], row[2]);
            return 0;
        }
        if (row[0] < end - PULSE_EPS) {
            cf_log(m, ST_ERROR, "logStatusError", "input step_segments row %d starts at %.17g s, before the "
                   "previous row with pulses ends (%.17g s): the rows must be in time order without overlap",
                   r, row[0], end);
            return 0;
        }
        end = row[0] + row[1];
    }
    return 1;
}

/* Point c at the first pulse of row r or later that is not before t - PULSE_EPS; 0 if none. */
static int segment_seek(const ModelInstance *m, int r, double t, Cursor *c) {
    for (; r < SEGMENT_ROWS; r++) {
        const double *row = &m->v.step_segments[3 * r];
        double k;
        if (row[2] == 0.0) {
            continue;
        }
        c->row = r;
        c->n = (int64_t)fabs(row[2]);
        c->start = row[0];
        c->duration = row[1];
        c->sign = row[2] > 0.0 ? 1 : -1;
        c->rate = (double)c->n / c->duration;
        k = ceil((t - PULSE_EPS - c->start) * (double)c->n / c->duration);
        c->k = k > 0.0 ? (k < (double)c->n ? (int64_t)k : c->n) : 0;
        while (c->k > 0 && segment_time(c, c->k - 1) >= t - PULSE_EPS) {
            c->k--;
        }
        while (c->k < c->n && segment_pulse_time(c) < t - PULSE_EPS) {
            c->k++;
        }
        if (c->k < c->n) {
            return 1;
        }
    }
    return 0;
}

static int segment_next(const ModelInstance *m, Cursor *c) {
    if (++c->k < c->n) {
        return 1;
    }
    return segment_seek(m, c->row + 1, -INFINITY, c);
}

/* -- FMI hooks ------------------------------------------------------------------------------- */
Status model_init(ModelInstance *m) {
    ModelState *s = &m->s;
    s->x.theta = 0.0;
    s->x.omega = 0.0;
    s->steps = 0;
    motor_command_table(m);
    motor_commanded_currents(m, &s->x.ia, &s->x.ib); /* the driver was on before the start */
    s->anchored = 0;
    s->rate = 0.0;
    s->phase = 0.0;
    s->t_anchor = m->time;
    s->next_pulse = 0;
    s->last_pulse_time = -1.0;
    s->pulse_updates = 0;
    s->rk4_steps = 0;
    s->base = s->x;
    s->t_base = m->time;
    s->grid_valid = 0;
    s->trig_uses = 0;
    inputs_changed(m);
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
    return check_phase(m) && check_segments(m) ? ST_OK : ST_ERROR;
}

void model_outputs(ModelInstance *m) {
    const ModelState *s = &m->s;
    const double nr = (double)rotor_teeth(m), mu = (double)m->v.microsteps;
    const double lead = m->v.screw_lead / 6.283185307179586;
    double z[3], error, full, ia, ib;
    MotorState x = s->x;
    Dynamics d;
    motor_dynamics(m, &d);
    if (d.ideal) {
        motor_commanded_currents(m, &ia, &ib);
        x.ia = ia;
        x.ib = ib;
    }
    m->v.commanded_steps = s->steps > INT32_MAX ? INT32_MAX : (s->steps < INT32_MIN ? INT32_MIN : (int32_t)s->steps);
    m->v.angle = x.theta;
    m->v.speed = x.omega;
    m->v.carriage_position = motor_carriage_position(m, x.theta);
    m->v.carriage_speed = x.omega * lead;
    error = (double)s->steps - x.theta * 4.0 * nr * mu / 6.283185307179586;
    m->v.position_error = error;
    full = fmin(fabs(error) / mu, 2.0e9); /* full steps (a tooth pitch is 4), kept in the Int32 range */
    m->v.lost_full_steps = full > 2.0 ? (int32_t)(4.0 * (floor((full - 2.0) / 4.0) + 1.0)) : 0;
    if (error < 0.0) {
        m->v.lost_full_steps = -m->v.lost_full_steps;
    }
    m->v.lost_steps = m->v.lost_full_steps != 0;
    motor_switch_indicators(m, x.theta, z);
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
    m->v.solver_pulse_updates = (double)s->pulse_updates;
    m->v.solver_rk4_steps = (double)s->rk4_steps;
}

/* The next pulse of either source after the ones due now [s]; INFINITY if none. */
static double next_pulse(const ModelState *s, int segments, const Cursor *cursor) {
    double tp = s->rate != 0.0 ? pulse_time(s, s->next_pulse) : INFINITY;
    if (segments) {
        const double ts = segment_pulse_time(cursor);
        tp = ts < tp ? ts : tp;
    }
    return tp;
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    ModelState *s = &m->s;
    double t = m->time;
    Dynamics d;
    Cursor cursor;
    int segments, restart;
    *event = 0;
    *t_reached = t_end;
    if (!(t_end > t)) {
        return ST_OK;
    }
    if (!check_phase(m) || !check_segments(m)) {
        return ST_ERROR;
    }
    latch_pulse_train(m, t);
    restart = inputs_changed(m);
    motor_dynamics(m, &d);
    segments = segment_seek(m, 0, t, &cursor);
    /* The pulse update continues its grid from the committed state unless something changed here: an
     * input of the equations, the next pulse (the grid's chunk ends there), or a pulse is due now. */
    if (d.pulse_update && s->grid_valid && !restart && s->t_base < t) {
        const double tp = next_pulse(s, segments, &cursor);
        const double b = tp > s->grid_a && tp < s->grid_a + SOLVER_CHUNK ? tp : s->grid_a + SOLVER_CHUNK;
        restart = tp <= t + PULSE_EPS || b != s->grid_b;
    } else {
        restart = 1;
    }
    if (restart) {
        s->base = s->x;
        s->t_base = t;
        s->grid_valid = 0;
    }
    for (;;) {
        const int direction = s->rate > 0.0 ? 1 : -1;
        double next = t_end, t_stop = t_end, tp;
        /* the pulses due now: within PULSE_EPS of t, and not at the step's end */
        while (s->rate != 0.0) {
            tp = pulse_time(s, s->next_pulse);
            if (tp > t + PULSE_EPS || tp >= t_end - PULSE_EPS) {
                break;
            }
            if (m->v.enable) {
                s->steps += direction;
                s->last_pulse_time = tp;
            }
            s->next_pulse++;
        }
        while (segments) {
            tp = segment_pulse_time(&cursor);
            if (tp > t + PULSE_EPS || tp >= t_end - PULSE_EPS) {
                break;
            }
            if (m->v.enable) {
                s->steps += cursor.sign;
                s->last_pulse_time = tp;
            }
            segments = segment_next(m, &cursor);
        }
        tp = next_pulse(s, segments, &cursor);
        if (tp < t_end - PULSE_EPS) {
            next = tp;
        }
        /* the commanded pulse rate over [t, next): bounds the solver's step with the rotor's speed */
        d.cmd_rate = fabs(s->rate);
        if (segments && cursor.k > 0) {
            d.cmd_rate = cursor.rate > d.cmd_rate ? cursor.rate : d.cmd_rate;
        }
        motor_commanded_currents(m, &d.ia_cmd, &d.ib_cmd);
        if (d.ideal) {
            s->x.ia = s->base.ia = d.ia_cmd;
            s->x.ib = s->base.ib = d.ib_cmd;
        }
        if (d.pulse_update ? motor_advance(m, &d, next, tp, m->early_return_allowed, &t_stop)
                           : motor_integrate(m, &d, t, next, m->early_return_allowed, &t_stop)) {
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

void model_event_indicators(ModelInstance *m, double *z) { motor_switch_indicators(m, m->s.x.theta, z); }
