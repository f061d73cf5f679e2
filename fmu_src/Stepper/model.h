/* Stepper: internal state (plain data: copied for FMU state get/set). */
#ifndef STEPPER_MODEL_H
#define STEPPER_MODEL_H

#include <stdint.h>

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
} ModelState;

#endif
