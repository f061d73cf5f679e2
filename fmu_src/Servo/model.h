/* Servo: internal state (plain data: copied for FMU state get/set). */
#ifndef SERVO_MODEL_H
#define SERVO_MODEL_H

#include <stdint.h>

/* -- encoder.c (identical in the Servo and Conveyor plants) ------------------------------------ */
typedef struct {
    int64_t count;     /* floor(position [counts]) */
    int64_t edge;      /* count boundary crossed by the last edge */
    int32_t direction; /* of the last edge: +1 up, -1 down */
    int32_t unused;
    double t_last;     /* instant of the last edge [s] */
    double t_prev;     /* instant of the edge before it [s] */
} Encoder;

/* A scalar function of the time since a segment's origin [s]. */
typedef double (*ScalarFn)(const void *ctx, double t);

/* The crossing of g in [a, b], where g(a) has not crossed and g(b) has (crossed: g > 0 if strict,
 * else g >= 0). Returns a time within tol after the crossing (g has crossed there). */
double root_after(ScalarFn g, const void *ctx, double a, double ga, double b, double gb, int strict, double tol);
void encoder_start(Encoder *e, double position, double t);
/* The position [counts] is monotonic on [a, b] (times since t_origin) and is pb at b. */
void encoder_track(Encoder *e, ScalarFn position, const void *ctx, double a, double b, double pb, double t_origin,
                   double tol);
int32_t wrap_int32(int64_t value);

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
