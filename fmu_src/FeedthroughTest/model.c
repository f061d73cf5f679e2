/* FeedthroughTest: a test model for input tables. Each output is its input, at once (direct
 * feedthrough: a getter after a setter sees the new value). With refuse_event_mode the FMI 3.0
 * build, which declares event mode, fails in fmi3UpdateDiscreteStates: an FMU that declares event
 * mode and refuses it, which an importer runs without event mode (as fmpy does by default). */
#include "cosim_fmu.h"

Status model_init(ModelInstance *m) {
    m->s.unused = 0;
    return ST_OK;
}

Status model_check(ModelInstance *m) {
    (void)m;
    return ST_OK;
}

void model_outputs(ModelInstance *m) {
    ModelData *v = &m->v;
    v->Float64_continuous_output = v->Float64_continuous_input;
    v->Float64_discrete_output = v->Float64_discrete_input;
    v->Int32_output = v->Int32_input;
    v->Boolean_output = v->Boolean_input;
}

Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event) {
    (void)m;
    *t_reached = t_end;
    *event = 0;
    return ST_OK;
}

Status model_event_update(ModelInstance *m, int *again) {
    *again = 0;
    if (m->v.refuse_event_mode) {
        cf_log(m, ST_ERROR, "logStatusError", "event mode is refused by this model (refuse_event_mode = true)");
        return ST_ERROR;
    }
    return ST_OK;
}

void model_event_indicators(ModelInstance *m, double *z) {
    (void)m;
    (void)z;
}
