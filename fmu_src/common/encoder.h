/* Quadrature encoder with exact edge instants, and the bracketing root finder (encoder.c).
 * Shared by the plants that list "encoder.c" and "encoder.h" under `shared` in their model.toml;
 * the build copies both into each FMU's sources/. */
#ifndef COSIM_ENCODER_H
#define COSIM_ENCODER_H

#include <stdint.h>

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

#endif
