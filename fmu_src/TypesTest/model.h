/* TypesTest: internal state (plain data: copied for FMU state get/set). */
#ifndef TYPESTEST_MODEL_H
#define TYPESTEST_MODEL_H

typedef struct {
    double position;       /* [m] integral of speed */
    int stage;             /* 1 before stage_time, 2 from it on */
    int pending_stage;     /* the event was reached with early return: stage 2 is set in event mode */
    int pending_terminate; /* the terminate request is made in event mode */
} ModelState;

#endif
