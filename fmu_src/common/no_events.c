/* The event hooks of a plant without events (FMI 3.0 hasEventMode = false, no event indicators):
 * nothing to update in event mode, no indicators. Shared by the plants that list "no_events.c"
 * under `shared` in their model.toml instead of writing these two functions in model.c. */
#include "cosim_fmu.h"

Status model_event_update(ModelInstance *m, int *again) {
    (void)m;
    *again = 0;
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) {
    (void)m;
    (void)z;
}
