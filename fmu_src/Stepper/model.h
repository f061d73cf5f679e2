/* Stepper: internal state (plain data: copied for FMU state get/set) and the motor's solver API
 * (motor.c), shared by model.c. */
#ifndef STEPPER_MODEL_H
#define STEPPER_MODEL_H

#include <stdint.h>

#define MAX_ELECTRICAL_STEPS 1024 /* microsteps per electrical turn: 4 * 256 */
#define SOLVER_CHUNK 1e-3         /* [s] the solvers choose their step size afresh at least this often */

/* Continuous state of the motor: rotor angle and speed, phase currents (used when L > 0). */
typedef struct {
    double theta; /* rotor angle [rad] */
    double omega; /* rotor speed [rad/s] */
    double ia;    /* phase A current [A] */
    double ib;    /* phase B current [A] */
} MotorState;

typedef struct {
    MotorState x;
    int64_t steps;          /* commanded microsteps (pulses accepted, signed) */
    /* The pulse train: pulse j of the current anchor is at t_anchor + (j - phase) / |rate|. */
    int anchored;           /* an anchor exists (set by the first step) */
    double rate;            /* step_rate the anchor was made from [1/s] */
    double phase;           /* step_phase the anchor was made from */
    double t_anchor;        /* step start at which the inputs were applied [s] */
    int64_t next_pulse;     /* index j of the next pulse not yet applied */
    double last_pulse_time; /* [s]; -1 before the first pulse */
    /* cos and sin of the commanded electrical angle after k microsteps, k = 0 .. 4 microsteps - 1 */
    double cmd_cos[MAX_ELECTRICAL_STEPS], cmd_sin[MAX_ELECTRICAL_STEPS];
    int table_turn;         /* 4 * microsteps once the table is made, else 0 */
    int64_t pulse_updates, rk4_steps; /* solver statistics: closed-form pulse updates, RK4 sub-steps */
    /* The pulse update's grid, anchored at pulses (not at communication points): x is the state at
     * the FMU's time, base the committed state at the grid point t_base <= time. The grid of the
     * chunk [grid_a, grid_b] has grid_n equal steps; base is at point grid_k. */
    MotorState base;
    double t_base, grid_a, grid_b;
    long grid_n, grid_k;
    int grid_valid;
    double last_load_torque, last_current; /* inputs at the last step: a change restarts the grid */
    int last_enable;
    /* sin and cos of Nr theta at the end of the last pulse update (theta = trig_theta), carried to
     * the next step instead of calling sin and cos again; recomputed every TRIG_REFRESH steps */
    double trig_theta, trig_sin, trig_cos;
    int trig_uses;
} ModelState;

/* Everything the derivative needs, fixed over one pulse interval (motor.c). */
typedef struct {
    double nr, kt, td, inertia, damping, friction, load;
    double ia_cmd, ib_cmd;
    double cmd_rate; /* [pulses/s] the commanded pulse rate (its magnitude) over the interval */
    int ideal; /* currents equal the commanded ones */
    double inductance, resistance, voltage, tau;
    double loop_gain;      /* L / current_tau [ohm] */
    double inv_inductance; /* 1 / L [1/H] (0 with an ideal source) */
    double h_fixed;        /* [s] the RK4 sub-step bound that does not depend on speed (see step_bound) */
    double h_pulse;        /* [s] the same bound for the pulse update (without max_step) */
    double inv_h_pulse;    /* 1 / h_pulse [1/s] */
    double electrical_per_step; /* [rad] electrical angle of one microstep */
    int pulse_update;      /* the closed-form pulse update may be used (else RK4 everywhere) */
} Dynamics;

struct ModelInstance;

/* motor.c */
void motor_dynamics(const struct ModelInstance *m, Dynamics *d);
void motor_commanded_currents(const struct ModelInstance *m, double *ia, double *ib);
void motor_command_table(struct ModelInstance *m);
double motor_torque(const Dynamics *d, const MotorState *x);
/* RK4 (the reference solver) on the state at the FMU's time from a to b (no pulse in between). With
 * stop_at_events, stop just after the first switch crossing: returns 1 and its time in *t_stop. */
int motor_integrate(struct ModelInstance *m, const Dynamics *d, double a, double b, int stop_at_events,
                    double *t_stop);
/* The pulse update on its grid: advance the committed state along the grid up to target (no pulse
 * in between; b_pulse, the next pulse or +inf, ends the grid's chunk), and the state at target
 * (not committed when it falls inside a grid step) into the state at the FMU's time. With
 * stop_at_events, stop just after the first switch crossing: returns 1 and its time in *t_stop. */
int motor_advance(struct ModelInstance *m, const Dynamics *d, double target, double b_pulse, int stop_at_events,
                  double *t_stop);
/* Switch indicators: >= 0 while tripped (limit_pos, limit_neg, home). */
void motor_switch_indicators(const struct ModelInstance *m, double theta, double *z);
double motor_carriage_position(const struct ModelInstance *m, double theta);

#endif
