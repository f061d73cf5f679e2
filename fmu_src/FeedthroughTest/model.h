/* FeedthroughTest: no internal state (plain data: copied for FMU state get/set). */
#ifndef FEEDTHROUGHTEST_MODEL_H
#define FEEDTHROUGHTEST_MODEL_H

typedef struct {
    int unused;
} ModelState;

#endif
