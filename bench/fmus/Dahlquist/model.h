/* Dahlquist (bench model): internal state. */
#ifndef DAHLQUIST_MODEL_H
#define DAHLQUIST_MODEL_H

typedef struct {
    double x;
} ModelState;

#endif
