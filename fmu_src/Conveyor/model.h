/* Conveyor: internal state (plain data: copied for FMU state get/set). */
#ifndef CONVEYOR_MODEL_H
#define CONVEYOR_MODEL_H

#include <stdint.h>

#include "encoder.h"

/* -- the belt --------------------------------------------------------------------------------- */
typedef struct {
    double h;            /* internal step [s] */
    double x;            /* belt position [m] */
    double v;            /* drive speed [m/s] (without disturbance and ripple) */
    int64_t mark_k;      /* index of the mark whose pitch interval holds the position */
    int mark_on;         /* a mark is under the sensor: position in [m_k, m_k + length) */
    int pending;         /* FMI 3 event mode: mark edge reached but not yet applied (+1 up, -1 down) */
    int64_t marks_seen;  /* rising edges of the sensor */
    double t_last_mark;  /* instant of the last rising edge [s] */
    Encoder enc;
} ModelState;

#endif
