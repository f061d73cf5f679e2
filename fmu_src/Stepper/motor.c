/* Stepper: the motor's equations and their two solvers.
 *
 *     T = -Kt ia sin(Nr theta) + Kt ib cos(Nr theta) - Td sin(4 Nr theta)
 *     J dw/dt = T - B w - T_load - T_friction
 *     L di/dt = clamp(R i + e + L (i_cmd - i) / current_tau, -V, V) - R i - e   (each phase, L > 0)
 *
 * Between two pulses the commanded currents are constant. Two solvers cover such an interval:
 *
 * 1. The pulse update (pulse_update(), used by default): one step per pulse interval (or per
 *    1/50 of the natural period, or per 0.25 rad of electrical angle, whichever is shorter). Each
 *    phase current is solved in closed form: while the loop's voltage is within the bus it is the
 *    loop's exact solution i_cmd + (i - i_cmd) exp(-t / current_tau); after a pulse that saturates
 *    the loop, L di/dt = +-V - R i - e(t) with the back-EMF linear in time is solved by its Taylor
 *    series up to the instant the loop's demand returns inside the bus (Newton's method), then the
 *    exact tracking solution. The rotor's change over the step is the double integral of its
 *    acceleration: the currents enter through their exact moments int t^k i(t) dt, the angle
 *    through cos and sin of Nr theta interpolated by quadratics over the step along a path of the
 *    rotor, which is first the Taylor path theta0 + w0 t + a0 t^2 / 2 and then the cubic Hermite
 *    path through the result (two passes: a Picard iteration). The step is refused, and RK4 takes
 *    it, where the assumptions fail: Coulomb friction (stick-slip), a phase whose loop saturates
 *    again inside the step, more than 0.5 rad of electrical angle within the step, a saturated
 *    span too long for the Taylor series (R t / L > 0.05), or two passes that differ by more than
 *    1e-4 of a microstep.
 * 2. RK4 (rk4(), the reference; everywhere with the parameter rk4_only): classic Runge-Kutta 4
 *    for the rotor on equal sub-steps (t = a + (b - a) i / n) no longer than max_step, 1/50 of the
 *    natural period and 0.25 rad of electrical angle. With L > 0 each rotor sub-step integrates the
 *    two phase currents first, on finer sub-steps of at most current_tau / 4 with the back-EMF
 *    linear in time over the rotor sub-step: the loop's exact solution where its voltage stays
 *    within the bus at both ends of a fine sub-step, RK4 where it saturates; the rotor's stages
 *    take the currents at the middle and the end.
 *
 * Switch crossings are located on RK4 sub-steps by the shared root finder (root_after, roots.c:
 * regula falsi, Illinois, with bisection) to a bracket narrower than EVENT_TOL; a pulse-update step
 * across which a switch changes is taken again by RK4. With FMI 3.0 early return the step stops
 * just after the crossing, otherwise the step goes on. */
#include <math.h>
#include <stdint.h>

#include "cosim_fmu.h"
#include "roots.h"

#define TWO_PI 6.283185307179586
#define EVENT_TOL 1e-11       /* [s] width of the bracket around a located switch crossing */
#define CHUNK SOLVER_CHUNK
#define N_SWITCHES 3
#define MAX_ANGLE_STEP 0.25   /* [rad] electrical angle per solver step (step bound, both solvers) */
#define MAX_ANGLE_UPDATE 0.5  /* [rad] electrical angle within a pulse-update step beyond which RK4 takes it */
#define MAX_DECAY_SATURATED 0.05 /* R t / L over a saturated span beyond which RK4 takes the step */
#define PICARD_TOL 1e-3       /* [microsteps] largest difference of the two passes of a pulse update */
#define TRIG_REFRESH 64       /* pulse updates that carry sin and cos of Nr theta before libm recomputes them */

static int rotor_teeth(const ModelInstance *m) { return m->v.steps_per_rev / 4; }

static double total_inertia(const ModelInstance *m) {
    double r = m->v.screw_lead / TWO_PI;
    return m->v.rotor_inertia + m->v.load_inertia + m->v.carriage_mass * r * r;
}

void motor_command_table(ModelInstance *m) {
    const int turn = 4 * m->v.microsteps;
    int k;
    for (k = 0; k < turn && k < MAX_ELECTRICAL_STEPS; k++) {
        const double angle = (double)k * (TWO_PI / (double)turn); /* exact modulo one electrical turn */
        m->s.cmd_cos[k] = cos(angle);
        m->s.cmd_sin[k] = sin(angle);
    }
    m->s.table_turn = turn <= MAX_ELECTRICAL_STEPS ? turn : 0;
}

/* The commanded phase currents I cos, I sin of the electrical angle after `steps` microsteps. */
void motor_commanded_currents(const ModelInstance *m, double *ia, double *ib) {
    const double amplitude = m->v.enable ? m->v.current : 0.0;
    const int64_t turn = 4 * (int64_t)m->v.microsteps;
    int64_t k;
    if (m->s.table_turn == turn) { /* turn is a power of two (model_check): steps modulo turn, in 0 .. turn - 1 */
        k = m->s.steps & (turn - 1);
        *ia = amplitude * m->s.cmd_cos[k];
        *ib = amplitude * m->s.cmd_sin[k];
        return;
    }
    k = m->s.steps % turn;
    if (k < 0) {
        k += turn;
    }
    {
        /* before the table is made (initialisation mode) */
        const double angle = (double)k * (TWO_PI / (double)turn);
        *ia = amplitude * cos(angle);
        *ib = amplitude * sin(angle);
    }
}

/* Everything of Dynamics but the commanded currents and the commanded rate: fixed over a doStep. */
void motor_dynamics(const ModelInstance *m, Dynamics *d) {
    double stiffness;
    d->nr = (double)rotor_teeth(m);
    d->kt = m->v.torque_constant;
    d->td = m->v.detent_torque;
    d->inertia = total_inertia(m);
    d->damping = m->v.viscous_damping;
    d->friction = m->v.friction_torque;
    d->load = m->v.load_torque;
    motor_commanded_currents(m, &d->ia_cmd, &d->ib_cmd);
    d->cmd_rate = 0.0;
    d->ideal = !(m->v.phase_inductance > 0.0);
    d->inductance = m->v.phase_inductance;
    d->resistance = m->v.phase_resistance;
    d->voltage = m->v.supply_voltage;
    d->tau = m->v.current_tau;
    d->loop_gain = d->ideal ? 0.0 : d->inductance / d->tau;
    d->inv_inductance = d->ideal ? 0.0 : 1.0 / d->inductance;
    /* RK4: max_step and 1/50 of the small-signal natural period (the current loop has its own
     * sub-steps); the pulse update: 1/25 of the natural period (and at most CHUNK) */
    d->h_fixed = m->v.max_step;
    d->h_pulse = CHUNK;
    stiffness = d->nr * (d->kt * m->v.current + 4.0 * d->td);
    if (stiffness > 0.0) {
        const double period = TWO_PI / sqrt(stiffness / d->inertia);
        d->h_fixed = fmin(d->h_fixed, period / 50.0);
        d->h_pulse = fmin(d->h_pulse, period / 25.0);
    }
    d->inv_h_pulse = 1.0 / d->h_pulse;
    d->electrical_per_step = TWO_PI / (4.0 * (double)m->v.microsteps);
    d->pulse_update = !m->v.rk4_only && !(d->friction > 0.0);
}

static double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

static double larger(double a, double b) { return a > b ? a : b; } /* fmax without its NaN rules (inlined) */

/* Motor torque from s = sin(Nr theta), c = cos(Nr theta); sin(4 Nr theta) = 4 s c (c^2 - s^2). */
static double torque_sc(const Dynamics *d, double ia, double ib, double s, double c) {
    return d->kt * (ib * c - ia * s) - d->td * 4.0 * s * c * (c * c - s * s);
}

double motor_torque(const Dynamics *d, const MotorState *x) {
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

/* -- RK4 (the reference solver) ------------------------------------------------------------ */
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

/* The electrical speed a step must follow [rad/s]: the faster of the rotor's and the command's. */
static double electrical_speed(const Dynamics *d, double omega) {
    return larger(d->nr * fabs(omega), d->cmd_rate * d->electrical_per_step);
}

/* Largest RK4 sub-step [s]: max_step, 1/50 of the small-signal natural period (Dynamics.h_fixed), and
 * 0.25 rad of electrical angle at the faster of the rotor's speed and the commanded speed. */
static double step_bound(const Dynamics *d, double omega) {
    const double speed = electrical_speed(d, omega);
    return speed > 0.0 ? fmin(d->h_fixed, MAX_ANGLE_STEP / speed) : d->h_fixed;
}

double motor_carriage_position(const ModelInstance *m, double theta) {
    return m->v.carriage_start + theta * m->v.screw_lead / TWO_PI;
}

void motor_switch_indicators(const ModelInstance *m, double theta, double *z) {
    const double x = motor_carriage_position(m, theta);
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
    motor_switch_indicators(c->m, x.theta, z);
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

/* Does a switch change between the angles theta0 and theta1? */
static int switch_changes(const ModelInstance *m, double theta0, double theta1) {
    double z0[N_SWITCHES], z1[N_SWITCHES];
    int k;
    motor_switch_indicators(m, theta0, z0);
    motor_switch_indicators(m, theta1, z1);
    for (k = 0; k < N_SWITCHES; k++) {
        if ((z0[k] >= 0.0) != (z1[k] >= 0.0)) {
            return 1;
        }
    }
    return 0;
}

/* RK4 on the state x from ca to cb on equal sub-steps. With stop_at_events, stop just after the
 * first switch crossing: returns 1 and its time in *t_stop. */
static int rk4_span(ModelInstance *m, const Dynamics *d, MotorState *x, double ca, double cb, int stop_at_events,
                    double *t_stop) {
    const double h = step_bound(d, x->omega);
    const long n = (long)ceil((cb - ca) / h - 1e-9) > 1 ? (long)ceil((cb - ca) / h - 1e-9) : 1;
    long i;
    for (i = 0; i < n; i++) {
        const double t0 = ca + (cb - ca) * (double)i / (double)n;
        const double t1 = i + 1 == n ? cb : ca + (cb - ca) * (double)(i + 1) / (double)n;
        MotorState x1;
        rk4(d, x, t1 - t0, &x1);
        m->s.rk4_steps++;
        if (stop_at_events) {
            double z0[N_SWITCHES], z1[N_SWITCHES], first = -1.0;
            int k;
            motor_switch_indicators(m, x->theta, z0);
            motor_switch_indicators(m, x1.theta, z1);
            for (k = 0; k < N_SWITCHES; k++) {
                if ((z0[k] >= 0.0) != (z1[k] >= 0.0)) {
                    const double s = locate_crossing(m, d, x, t1 - t0, k, z0[k], z1[k]);
                    if (first < 0.0 || s < first) {
                        first = s;
                    }
                }
            }
            if (first >= 0.0) {
                MotorState xe;
                rk4(d, x, first, &xe);
                *x = xe;
                *t_stop = t0 + first;
                return 1;
            }
        }
        *x = x1;
    }
    return 0;
}

/* -- the pulse update ---------------------------------------------------------------------- */
#define N_NODES 3   /* quadratic interpolation of the angle's cos and sin over a step: nodes at 0, 1/2, 1 */
#define N_MOMENTS 4 /* int_0^1 x^k i(h x) dx, k = 0 .. 3 */
#define PASSES 2    /* the moments along the Taylor path, then the nodes along the Hermite path through its result */
static const double NODE[N_NODES] = {0.0, 0.5, 1.0};
static const double SIXTH = 1.0 / 6.0;

/* One phase's current over a step [0, h] in the normalised time x = t / h: the Taylor polynomial
 * sum p[j] x^j while the loop is saturated (x < sat), then i_cmd + delta exp(-kappa (x - sat)). */
typedef struct {
    double m[N_MOMENTS]; /* moments int_0^1 x^k i dx */
    double end;          /* i at x = 1 */
} Profile;

static const double INV[17] = {0.0, 1.0, 1.0 / 2, 1.0 / 3, 1.0 / 4, 1.0 / 5, 1.0 / 6, 1.0 / 7, 1.0 / 8, 1.0 / 9,
                                1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13, 1.0 / 14, 1.0 / 15, 1.0 / 16}; /* 1 / k */
static const double BINOMIAL[N_MOMENTS][N_MOMENTS] = {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}};

/* b[j] = int_0^l y^j exp(-kappa y) dy, j = 0 .. N_MOMENTS - 1; returns exp(-kappa l). */
static double exp_moments(double kappa, double l, double b[N_MOMENTS]) {
    const double lambda = kappa * l, decay = exp(-lambda);
    int j;
    if (lambda >= 0.25) {
        const double inv_kappa = 1.0 / kappa;
        double lj = 1.0;
        b[0] = (1.0 - decay) * inv_kappa;
        for (j = 1; j < N_MOMENTS; j++) {
            lj *= l;
            b[j] = ((double)j * b[j - 1] - lj * decay) * inv_kappa;
        }
    } else {
        /* b[j] = l^(j+1) sum_n (-lambda)^n / (n! (n + j + 1)): the recurrence above cancels here */
        double term = 1.0, lj = l;
        double sum[N_MOMENTS] = {0.0};
        int n;
        for (n = 0; n < 12; n++) {
            for (j = 0; j < N_MOMENTS; j++) {
                sum[j] += term * INV[n + j + 1];
            }
            term *= -lambda * INV[n + 1];
        }
        for (j = 0; j < N_MOMENTS; j++) {
            b[j] = lj * sum[j];
            lj *= l;
        }
    }
    return decay;
}

/* The moments of i_cmd + delta exp(-kappa (x - sat)) over [sat, 1] added to p; returns exp(-kappa (1 - sat)). */
static double add_tracking(double i_cmd, double delta, double kappa, double sat, Profile *p) {
    double b[N_MOMENTS], power[N_MOMENTS], sk = sat, decay;
    int k, j;
    if (kappa * (1.0 - sat) >= 0.25) {
        /* M_k = int_sat^1 x^k exp(-kappa (x - sat)) dx by parts: M_k = (sat^k - E + k M_(k-1)) / kappa */
        const double inv_kappa = 1.0 / kappa;
        double moment, satk = 1.0;
        decay = exp(-kappa * (1.0 - sat));
        moment = (1.0 - decay) * inv_kappa;
        for (k = 0; k < N_MOMENTS; k++) {
            if (k > 0) {
                satk *= sat;
                moment = (satk - decay + (double)k * moment) * inv_kappa;
            }
            p->m[k] += i_cmd * (1.0 - sk) * INV[k + 1] + delta * moment;
            sk *= sat;
        }
        p->end = i_cmd + delta * decay;
        return decay;
    }
    decay = exp_moments(kappa, 1.0 - sat, b);
    power[0] = 1.0;
    for (k = 1; k < N_MOMENTS; k++) {
        power[k] = power[k - 1] * sat;
    }
    for (k = 0; k < N_MOMENTS; k++) {
        /* int_sat^1 x^k dx and int_0^l (sat + y)^k exp(-kappa y) dy (binomial expansion) */
        double sum = 0.0;
        for (j = 0; j <= k; j++) {
            sum += BINOMIAL[k][j] * power[k - j] * b[j];
        }
        p->m[k] += i_cmd * (1.0 - sk) * INV[k + 1] + delta * sum;
        sk *= sat;
    }
    p->end = i_cmd + delta * decay;
    return decay;
}

/* Is the loop's demand R i + e + g (i_cmd - i) within the bus over the tracking span [t_sat, h],
 * where i = i_cmd + delta exp(-(t - t_sat) / tau) and e = e0 + e1 t? */
static int tracking_within_bus(const Dynamics *d, double i_cmd, double delta, double e0, double e1, double t_sat,
                               double h, double decay) {
    const double v = d->voltage * (1.0 + 1e-9), gain = d->loop_gain - d->resistance;
    const double base = d->resistance * i_cmd, at_end = base + e0 + e1 * h + gain * delta * decay;
    double q;
    if (fabs(at_end) > v) {
        return 0;
    }
    if (larger(fabs(base + e0 + e1 * t_sat), fabs(base + e0 + e1 * h)) + fabs(gain * delta) <= v) {
        return 1;
    }
    /* an extremum inside: dD/dt = e1 - gain delta exp(-(t - t_sat) / tau) / tau = 0 */
    q = gain * delta != 0.0 ? e1 * d->tau / (gain * delta) : 0.0;
    if (q > decay && q < 1.0) {
        const double t = t_sat - d->tau * log(q);
        return fabs(base + e0 + e1 * t + gain * delta * q) <= v;
    }
    return 1;
}

/* The tracking solution's moments from the step's start, shared by the phases: b[k] = int_0^1 x^k
 * exp(-kappa x) dx and exp(-kappa) (made when a phase first needs them). */
typedef struct {
    double b[N_MOMENTS], decay;
    int ready;
} Basis;

/* The current of one phase over [0, h] from i0 towards i_cmd with the back-EMF e0 + e1 t; 0 if the
 * closed form does not hold (RK4 must take the step). */
static int phase_profile(const Dynamics *d, double i0, double i_cmd, double e0, double e1, double h, Basis *basis,
                         Profile *p) {
    const double kappa = h / d->tau, d0 = demand(d, i0, i_cmd, e0);
    double sat = 0.0, start = i0, decay;
    int k;
    if (fabs(d0) <= d->voltage) {
        const double delta = i0 - i_cmd;
        if (!basis->ready) {
            basis->decay = exp_moments(kappa, 1.0, basis->b);
            basis->ready = 1;
        }
        for (k = 0; k < N_MOMENTS; k++) {
            p->m[k] = i_cmd * INV[k + 1] + delta * basis->b[k];
        }
        p->end = i_cmd + delta * basis->decay;
        return tracking_within_bus(d, i_cmd, delta, e0, e1, 0.0, h, basis->decay);
    }
    for (k = 0; k < N_MOMENTS; k++) {
        p->m[k] = 0.0;
    }
    {
        /* saturated at v: L i' = v - R i - e0 - e1 t, by its Taylor series i0 + c1 t + c2 t^2 + c3 t^3 */
        const double v = d0 > 0.0 ? d->voltage : -d->voltage, r = d->resistance, l = d->inductance;
        const double c1 = (v - r * i0 - e0) / l, c2 = (-r * c1 - e1) / (2.0 * l), c3 = -r * c2 / (3.0 * l);
        const double gain = r - d->loop_gain;
        const double f0 = d0 - v, df0 = gain * c1 + e1;
        double t;
        int j;
        /* f(t) = demand - v = (R - g) i(t) + e0 + e1 t + g i_cmd - v: its first root in (0, h], from
         * the root of its tangent at 0 and one Newton step (f is nearly linear where R t / L is small,
         * which leaves an error below 1e-6 of the span; the current is smooth (C1) at the switch-over) */
        t = f0 * df0 < 0.0 ? -f0 / df0 : h;
        if (t < h) {
            const double f = gain * (i0 + t * (c1 + t * (c2 + t * c3))) + e0 + e1 * t + d->loop_gain * i_cmd - v;
            const double df = gain * (c1 + t * (2.0 * c2 + t * 3.0 * c3)) + e1;
            t = clamp(t - f / df, 0.0, h);
        } else {
            const double fh = gain * (i0 + h * (c1 + h * (c2 + h * c3))) + e0 + e1 * h + d->loop_gain * i_cmd - v;
            if ((fh > 0.0) != (f0 > 0.0)) {
                return 0; /* it leaves the bus late, against its start: RK4 */
            }
            t = h; /* saturated over the whole step */
        }
        if (r * t / l > MAX_DECAY_SATURATED) {
            return 0; /* the Taylor series is exact enough over the saturated span only while R t / L is small */
        }
        sat = t / h;
        {
            const double q[4] = {i0, c1 * h, c2 * h * h, c3 * h * h * h};
            double sk = sat;
            for (k = 0; k < N_MOMENTS; k++) {
                double sj = sk;
                for (j = 0; j < 4; j++) {
                    p->m[k] += q[j] * sj * INV[k + j + 1];
                    sj *= sat;
                }
                sk *= sat;
            }
            start = q[0] + sat * (q[1] + sat * (q[2] + sat * q[3]));
        }
        if (t >= h) {
            p->end = start;
            return 1;
        }
        decay = add_tracking(i_cmd, start - i_cmd, kappa, sat, p);
        return tracking_within_bus(d, i_cmd, start - i_cmd, e0, e1, t, h, decay);
    }
}

/* cos and sin of a small angle u by their Taylor series (|u| <= MAX_ANGLE_UPDATE: error below 1e-13). */
static void small_cos_sin(double u, double *c, double *s) {
    static const double C2 = -1.0 / 2, C4 = 1.0 / 24, C6 = -1.0 / 720, C8 = 1.0 / 40320, C10 = -1.0 / 3628800,
                        C12 = 1.0 / 479001600;
    static const double S3 = -1.0 / 6, S5 = 1.0 / 120, S7 = -1.0 / 5040, S9 = 1.0 / 362880, S11 = -1.0 / 39916800;
    const double u2 = u * u;
    *c = 1.0 + u2 * (C2 + u2 * (C4 + u2 * (C6 + u2 * (C8 + u2 * (C10 + u2 * C12)))));
    *s = u * (1.0 + u2 * (S3 + u2 * (S5 + u2 * (S7 + u2 * (S9 + u2 * S11)))));
}

/* Coefficients of the quadratic through y at x = 0, 1/2, 1. */
static void quadratic(const double y[N_NODES], double q[N_NODES]) {
    q[0] = y[0];
    q[1] = -3.0 * y[0] + 4.0 * y[1] - y[2];
    q[2] = 2.0 * y[0] - 4.0 * y[1] + 2.0 * y[2];
}

/* The rotor's state at the end of a step from the integrals of the torque over it, and the cubic
 * Hermite path through it (the next pass's path: theta0 + w0 t + alpha t^2 / 2 + beta t^3 / 6).
 * i0, i1: int_0^1 i_q dx and int_0^1 (1 - x) i_q dx of Kt's current term; detent0, detent1 the same of
 * sin(4 Nr theta); alpha, beta: the path the damping was taken along (updated). */
static void pass_result(const Dynamics *d, const MotorState *x0, double h, double i0, double i1, double detent0,
                        double detent1, double *alpha, double *beta, double *theta_h, double *omega_h) {
    const double w0 = x0->omega, inv_inertia = 1.0 / d->inertia, inv_h = 1.0 / h;
    /* damping along the path: int_0^h w dt and int_0^h (h - t) w dt */
    const double path1 = h * (w0 + h * (0.5 * *alpha + h * SIXTH * *beta));
    const double path2 = h * h * (0.5 * w0 + h * (SIXTH * *alpha + h * (SIXTH / 4.0) * *beta));
    double d_theta, d_omega;
    *omega_h = w0 + (h * (d->kt * i0 - d->td * detent0) - d->damping * path1 - d->load * h) * inv_inertia;
    *theta_h = x0->theta + w0 * h +
               (h * h * (d->kt * i1 - d->td * detent1) - d->damping * path2 - d->load * h * h / 2.0) * inv_inertia;
    d_theta = *theta_h - x0->theta - w0 * h;
    d_omega = *omega_h - w0;
    *beta = (6.0 * d_omega * h - 12.0 * d_theta) * inv_h * inv_h * inv_h;
    *alpha = (d_omega - *beta * h * h / 2.0) * inv_h;
}

/* One step of size h from x0 by the pulse update (see the file's head); 0 if RK4 must take it.
 * s carries sin and cos of Nr theta from one step's end to the next step's start. */
static int pulse_update(const Dynamics *d, ModelState *s, const MotorState *x0, double h, MotorState *x1) {
    static const double weight0[N_NODES] = {1.0, 1.0 / 2.0, 1.0 / 3.0};    /* int_0^1 x^k dx */
    static const double weight1[N_NODES] = {1.0 / 2.0, 1.0 / 6.0, 1.0 / 12.0}; /* int_0^1 (1 - x) x^k dx */
    const int carried = s->trig_uses > 0 && s->trig_uses < TRIG_REFRESH && s->trig_theta == x0->theta;
    const double phi0 = d->nr * x0->theta;
    const double s0 = carried ? s->trig_sin : sin(phi0), c0 = carried ? s->trig_cos : cos(phi0);
    const double w0 = x0->omega, a0 = acceleration(d, w0, x0->ia, x0->ib, s0, c0);
    double c_end = c0, s_end = s0;
    Profile pa, pb;
    double alpha = a0, beta = 0.0, theta_h = 0.0, omega_h = 0.0, first;
    int pass, k;
    if (d->ideal) {
        for (k = 0; k < N_MOMENTS; k++) {
            pa.m[k] = d->ia_cmd * INV[k + 1];
            pb.m[k] = d->ib_cmd * INV[k + 1];
        }
        pa.end = d->ia_cmd;
        pb.end = d->ib_cmd;
    } else {
        const double ws = d->kt * w0, spin = d->nr * w0 * w0;
        Basis basis;
        basis.ready = 0;
        if (!phase_profile(d, x0->ia, d->ia_cmd, -ws * s0, -d->kt * (a0 * s0 + spin * c0), h, &basis, &pa) ||
            !phase_profile(d, x0->ib, d->ib_cmd, ws * c0, d->kt * (a0 * c0 - spin * s0), h, &basis, &pb)) {
            return 0;
        }
    }
    {
        /* first pass, from the moments alone: cos and sin of Nr theta to first order in the angle
         * u = U1 x + U2 x^2 of the Taylor path theta0 + w0 t + a0 t^2 / 2 */
        const double u1 = d->nr * w0 * h, u2 = 0.5 * d->nr * a0 * h * h;
        const double cc = c0 * c0 - s0 * s0, s4 = 4.0 * s0 * c0 * cc, c4 = cc * cc - 4.0 * s0 * s0 * c0 * c0;
        const double *ma = pa.m, *mb = pb.m;
        const double i0 = c0 * mb[0] - s0 * (u1 * mb[1] + u2 * mb[2]) - s0 * ma[0] - c0 * (u1 * ma[1] + u2 * ma[2]);
        const double i1 = c0 * (mb[0] - mb[1]) - s0 * (u1 * (mb[1] - mb[2]) + u2 * (mb[2] - mb[3])) -
                          s0 * (ma[0] - ma[1]) - c0 * (u1 * (ma[1] - ma[2]) + u2 * (ma[2] - ma[3]));
        const double detent0 = s4 + 4.0 * c4 * (u1 / 2.0 + u2 / 3.0), detent1 = s4 / 2.0 + 4.0 * c4 * (u1 * SIXTH + u2 / 12.0);
        pass_result(d, x0, h, i0, i1, detent0, detent1, &alpha, &beta, &theta_h, &omega_h);
        first = theta_h;
    }
    for (pass = 1; pass < PASSES; pass++) {
        /* then along the Hermite path through the previous pass's result: cos and sin of Nr theta at
         * x = 1/2 and 1, interpolated by quadratics */
        double cq[N_NODES], sq[N_NODES], dq[N_NODES], cy[N_NODES], sy[N_NODES], dy[N_NODES];
        double i0 = 0.0, i1 = 0.0, detent0 = 0.0, detent1 = 0.0;
        cy[0] = c0;
        sy[0] = s0;
        for (k = 1; k < N_NODES; k++) {
            const double t = h * NODE[k];
            const double u = d->nr * t * (w0 + t * (0.5 * alpha + t * SIXTH * beta));
            double cu, su;
            if (!(fabs(u) <= MAX_ANGLE_UPDATE)) {
                return 0;
            }
            small_cos_sin(u, &cu, &su);
            cy[k] = c0 * cu - s0 * su;
            sy[k] = s0 * cu + c0 * su;
        }
        for (k = 0; k < N_NODES; k++) {
            dy[k] = 4.0 * sy[k] * cy[k] * (cy[k] * cy[k] - sy[k] * sy[k]); /* sin(4 Nr theta) */
        }
        quadratic(cy, cq);
        quadratic(sy, sq);
        quadratic(dy, dq);
        c_end = cy[N_NODES - 1];
        s_end = sy[N_NODES - 1];
        for (k = 0; k < N_NODES; k++) {
            i0 += cq[k] * pb.m[k] - sq[k] * pa.m[k];
            i1 += cq[k] * (pb.m[k] - pb.m[k + 1]) - sq[k] * (pa.m[k] - pa.m[k + 1]);
            detent0 += dq[k] * weight0[k];
            detent1 += dq[k] * weight1[k];
        }
        pass_result(d, x0, h, i0, i1, detent0, detent1, &alpha, &beta, &theta_h, &omega_h);
    }
    if (!(fabs(theta_h - first) * d->nr <= PICARD_TOL * d->electrical_per_step)) {
        return 0;
    }
    {
        /* cos and sin at the end: the last nodes' values (on the path through the first pass's
         * result) turned by the small difference of the two passes */
        const double delta = d->nr * (theta_h - first), d2 = delta * delta; /* |delta| < 1e-3 rad: error < 1e-17 */
        const double cd = 1.0 - 0.5 * d2 * (1.0 - d2 / 12.0), sd = delta * (1.0 - d2 * SIXTH);
        s->trig_cos = c_end * cd - s_end * sd;
        s->trig_sin = s_end * cd + c_end * sd;
        s->trig_theta = theta_h;
        s->trig_uses = carried ? s->trig_uses + 1 : 1;
    }
    x1->theta = theta_h;
    x1->omega = omega_h;
    x1->ia = pa.end;
    x1->ib = pb.end;
    return 1;
}

/* Pulse-update steps over a span [s]: each at most 1/50 of the natural period and 0.25 rad of
 * electrical angle at the speed at its start. */
static long pulse_steps(const Dynamics *d, double omega, double span) {
    const double steps = larger(span * d->inv_h_pulse, span * electrical_speed(d, omega) * (1.0 / MAX_ANGLE_STEP));
    return steps > 1.0 ? (long)ceil(steps - 1e-9) : 1;
}

int motor_integrate(ModelInstance *m, const Dynamics *d, double a, double b, int stop_at_events, double *t_stop) {
    const double span = b - a;
    const long chunks = span > CHUNK && (long)ceil(span / CHUNK - 1e-9) > 1 ? (long)ceil(span / CHUNK - 1e-9) : 1;
    long c;
    for (c = 0; c < chunks; c++) {
        const double ca = c == 0 ? a : a + span * (double)c / (double)chunks;
        const double cb = c + 1 == chunks ? b : a + span * (double)(c + 1) / (double)chunks;
        if (rk4_span(m, d, &m->s.x, ca, cb, stop_at_events, t_stop)) {
            return 1;
        }
    }
    return 0;
}

/* One step of the grid from the state x at t0 to t1 (committed or not: the caller decides): the
 * pulse update, or RK4 where it does not hold or a switch changes inside (RK4 then locates it). */
static int grid_step(ModelInstance *m, const Dynamics *d, MotorState *x, double t0, double t1, int stop_at_events,
                     double *t_stop) {
    MotorState x1;
    if (pulse_update(d, &m->s, x, t1 - t0, &x1) && !(stop_at_events && switch_changes(m, x->theta, x1.theta))) {
        *x = x1;
        m->s.pulse_updates++;
        return 0;
    }
    return rk4_span(m, d, x, t0, t1, stop_at_events, t_stop);
}

int motor_advance(ModelInstance *m, const Dynamics *d, double target, double b_pulse, int stop_at_events,
                  double *t_stop) {
    ModelState *s = &m->s;
    for (;;) {
        if (!s->grid_valid || s->grid_k == s->grid_n) {
            /* a new chunk from the committed state: up to the next pulse, at most CHUNK long */
            s->grid_a = s->t_base;
            s->grid_b = b_pulse > s->grid_a && b_pulse < s->grid_a + CHUNK ? b_pulse : s->grid_a + CHUNK;
            s->grid_n = pulse_steps(d, s->base.omega, s->grid_b - s->grid_a);
            s->grid_k = 0;
            s->grid_valid = 1;
        }
        while (s->grid_k < s->grid_n) {
            const long k = s->grid_k;
            const double t1 = k + 1 == s->grid_n ? s->grid_b
                                                 : s->grid_a + (s->grid_b - s->grid_a) * (double)(k + 1) / (double)s->grid_n;
            if (t1 > target) {
                break;
            }
            if (grid_step(m, d, &s->base, s->t_base, t1, stop_at_events, t_stop)) {
                s->t_base = *t_stop;
                s->x = s->base;
                s->grid_valid = 0; /* a new grid from the switch crossing */
                return 1;
            }
            s->t_base = t1;
            s->grid_k = k + 1;
        }
        if (s->t_base >= target) {
            s->x = s->base;
            return 0;
        }
        if (s->grid_k < s->grid_n) {
            /* the target lies inside a grid step: its state there, not committed (nor counted) */
            const int64_t updates = s->pulse_updates, rk4_steps = s->rk4_steps;
            MotorState x = s->base;
            const int crossed = grid_step(m, d, &x, s->t_base, target, stop_at_events, t_stop);
            s->pulse_updates = updates;
            s->rk4_steps = rk4_steps;
            if (crossed) {
                s->base = s->x = x;
                s->t_base = *t_stop;
                s->grid_valid = 0;
                return 1;
            }
            s->x = x;
            return 0;
        }
    }
}
