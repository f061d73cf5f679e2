/* BouncingBall (bench model): internal state. */
#ifndef BOUNCINGBALL_MODEL_H
#define BOUNCINGBALL_MODEL_H

typedef struct {
    double h, v;
    int resting; /* bounced below V_MIN: the ball lies on the floor */
    int pending; /* FMI 3.0 event mode: the floor was reached, the bounce is applied in event mode */
} ModelState;

#endif
