/* VanDerPol (bench model): internal state. */
#ifndef VANDERPOL_MODEL_H
#define VANDERPOL_MODEL_H

typedef struct {
    double x0, x1;
} ModelState;

#endif
