/* Laser: internal state (plain data: copied for FMU state get/set). */
#ifndef LASER_MODEL_H
#define LASER_MODEL_H

#include <stdint.h>

typedef struct {
    double power;     /* optical power [W] at the instance's time */
    double energy;    /* delivered energy [J] */
    int32_t periods;  /* rising edges of the modulation output so far */
    int mod_prev;     /* modulation level just before the instance's time (left limit) */
} ModelState;

#endif
