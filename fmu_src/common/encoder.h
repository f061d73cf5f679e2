/* Quadrature encoder with exact edge instants (encoder.c), located with root_after (roots.h).
 * Shared by the plants that list "encoder.c" and "encoder.h" (and roots.c, roots.h) under
 * `shared` in their model.toml; the build copies them into each FMU's sources/. */
#ifndef COSIM_ENCODER_H
#define COSIM_ENCODER_H

#include <stdint.h>

#include "roots.h"

typedef struct {
    int64_t count;     /* floor(position [counts]) */
    int64_t edge;      /* count boundary crossed by the last edge */
    int32_t direction; /* of the last edge: +1 up, -1 down */
    int32_t unused;
    double t_last;     /* instant of the last edge [s] */
    double t_prev;     /* instant of the edge before it [s] */
} Encoder;

void encoder_start(Encoder *e, double position, double t);
/* The position [counts] is monotonic on [a, b] (times since t_origin) and is pb at b. */
void encoder_track(Encoder *e, ScalarFn position, const void *ctx, double a, double b, double pb, double t_origin,
                   double tol);
int32_t wrap_int32(int64_t value);
/* The encoder outputs of a plant: count and last edge (wrapped to Int32), its direction, the
 * instants of the last two edges [s]. */
void encoder_outputs(const Encoder *e, int32_t *count, int32_t *edge, int32_t *direction, double *t_last,
                     double *t_prev);

#endif
