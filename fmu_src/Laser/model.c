/* Laser: a laser source behind a motion controller's PWM output.
 *
 * The carrier is resolved exactly inside the FMU: a period starts at clock tick
 * pwm_phase + k * pwm_period and is on for pwm_on ticks. Within each constant piece the optical
 * power follows a first-order lag whose solution is closed form:
 *
 *     P(t) = Pt + (P0 - Pt) exp(-t / tau),  E(t) = Pt t + (P0 - Pt) tau (1 - exp(-t / tau)),
 *
 * with tau = tau_rise while the target Pt is above P and tau_fall otherwise. A step of any length
 * walks the carrier edges with an integer period counter k (edge times are never summed), so the
 * result does not depend on the communication grid. */
#include <float.h>
#include <math.h>

#include "cosim_fmu.h"

/* Time [s] as modulation clock ticks, snapped to a whole tick when within floating-point noise. */
static double clock_ticks(const ModelInstance *m, double t) {
    double u = t * m->v.clock_frequency;
    double whole = nearbyint(u);
    double noise = fmax(1e-6, 8.0 * DBL_EPSILON * fabs(u));
    return fabs(u - whole) <= noise ? whole : u;
}

static int active(const ModelInstance *m) { return m->v.enable && m->v.gate; }

static int lases(const ModelInstance *m) {
    const int32_t on = m->v.pwm_on, period = m->v.pwm_period;
    if (!active(m) || on <= 0) {
        return 0;
    }
    return on >= period || (double)on >= m->v.duty_threshold * (double)period;
}

/* Position of tick u inside its carrier period, in [0, period). */
static double carrier_offset(const ModelInstance *m, double u) {
    double r = fmod(u - (double)m->v.pwm_phase, (double)m->v.pwm_period);
    return r < 0.0 ? r + (double)m->v.pwm_period : r;
}

/* Modulation level on [u, u+) (right) or (u-, u] (left) with the current inputs. */
static int level(const ModelInstance *m, double u, int left) {
    const int32_t on = m->v.pwm_on, period = m->v.pwm_period;
    double r;
    if (!active(m) || on <= 0) {
        return 0;
    }
    if (on >= period) {
        return 1;
    }
    r = carrier_offset(m, u);
    return left ? (r > 0.0 && r <= (double)on) : (r < (double)on);
}

/* Advance power and energy over dt_ticks clock ticks towards target [W]. */
static void settle(ModelInstance *m, double target, double dt_ticks) {
    ModelState *s = &m->s;
    double dt = dt_ticks / m->v.clock_frequency;
    double tau = target > s->power ? m->v.tau_rise : m->v.tau_fall;
    double decay;
    if (dt <= 0.0) {
        return;
    }
    decay = exp(-dt / tau);
    s->energy += target * dt + (s->power - target) * tau * (1.0 - decay);
    s->power = target + (s->power - target) * decay;
}

Status model_init(ModelInstance *m) {
    m->s.power = 0.0;
    m->s.energy = 0.0;
    m->s.periods = 0;
    m->s.mod_prev = 0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    double u = clock_ticks(m, m->time);
    int now = level(m, u, 0);
    m->v.power = m->s.power;
    m->v.energy = m->s.energy;
    m->v.modulation = now;
    m->v.pwm_periods = m->s.periods + (now && !m->s.mod_prev ? 1 : 0);
    m->v.lasing = lases(m);
}

/* Advance from the instance's time to t_end (the body of one doStep). */
static void step_to(ModelInstance *m, double t_end) {
    const double ua = clock_ticks(m, m->time), ub = clock_ticks(m, t_end);
    const double period = (double)m->v.pwm_period, on = (double)m->v.pwm_on, phase = (double)m->v.pwm_phase;
    const double peak = lases(m) ? m->v.peak_power : 0.0;
    ModelState *s = &m->s;
    if (ub <= ua) {
        return;
    }
    if (level(m, ua, 0) && !s->mod_prev) {
        s->periods++; /* the output rises at the start of this step */
    }
    if (!active(m) || on <= 0.0 || on >= period) {
        settle(m, level(m, ua, 0) ? peak : 0.0, ub - ua);
    } else {
        double k = floor((ua - phase) / period);
        double u = ua;
        for (;;) {
            const double rise = phase + k * period, fall = rise + on, next = rise + period;
            double end;
            if (u < fall) {
                end = fmin(fall, ub);
                settle(m, peak, end - u);
                u = end;
            }
            if (u >= ub) {
                break;
            }
            end = fmin(next, ub);
            settle(m, 0.0, end - u);
            u = end;
            if (u >= ub) {
                break;
            }
            k += 1.0; /* a period starts strictly inside the step */
            s->periods++;
        }
    }
    s->mod_prev = level(m, ub, 1);
}

/* One doStep to t_end, stopping at the instants of sample_schedule inside it (FMI 3.0): at each, as if a
 * doStep ended there (end of the step before it: row[0]) and the next began (row[1]), the outputs are
 * computed and power and energy kept in the sample arrays. */
Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    int32_t taken = 0;
#ifdef N_SAMPLE_SCHEDULE
    int k;
    for (k = 0; k < N_POWER_SAMPLES; k++) {
        const double end = m->v.sample_schedule[2 * k], next = m->v.sample_schedule[2 * k + 1];
        if (!(next > m->time) || !(end < t_end) || !(next < t_end)) {
            break; /* the list ends at the first row not after the instance's time */
        }
        step_to(m, end);
        m->time = end;
        model_outputs(m);
        m->v.power_samples[taken] = m->v.power;
        m->v.energy_samples[taken] = m->v.energy;
        taken++;
        m->time = next;
    }
    m->v.samples_taken[0] = taken;
#endif
    (void)taken;
    *event = 0;
    *t_reached = t_end;
    step_to(m, t_end);
    return ST_OK;
}
