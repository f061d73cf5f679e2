/* Servo: internal state (plain data: copied for FMU state get/set). */
#ifndef SERVO_MODEL_H
#define SERVO_MODEL_H

#include <stdint.h>

#include "encoder.h"

/* -- the motor -------------------------------------------------------------------------------- */
typedef struct {
    /* constants of the linear part, fixed at initialisation: d/dt [i, w] = A [i, w] + b */
    double a11, a12, a21, a22; /* A */
    double det;                /* det A > 0 */
    double mu;                 /* trace / 2 */
    double q;                  /* mu^2 - det: > 0 two real eigenvalues, < 0 a complex pair */
    double l1, l2;             /* real eigenvalues (q > 0) */
    double nu;                 /* damped angular frequency (q < 0) */
    double h;                  /* internal step [s] */
    /* state at the instance's time */
    double i;                  /* armature current [A] */
    double w;                  /* speed [rad/s] */
    double theta;              /* angle [rad] */
    int stuck;                 /* Coulomb friction holds the rotor (w == 0) */
    int dir;                   /* direction of motion while slipping: sign of the Coulomb torque */
    Encoder enc;
} ModelState;

#endif
