/* cosim plant FMUs: the interface between a plant model and the FMI 2.0 / 3.0 wrappers.
 *
 * A plant folder holds model.toml (its variables, from which the build generates model_vars.h,
 * model_vars.c and both modelDescription.xml files), model.h (its internal state) and model.c
 * (the functions declared at the end of this header). The wrappers fmi2_cs.c and fmi3_cs.c turn
 * those functions into the FMI API. Every instance owns all of its data: there is no global state,
 * so any number of instances can live in one process.
 */
#ifndef COSIM_FMU_H
#define COSIM_FMU_H

#include <stddef.h>
#include <stdint.h>

typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } Status;

typedef enum { VT_FLOAT64, VT_INT32, VT_BOOL } VarType;

typedef enum { CA_INDEPENDENT, CA_PARAMETER, CA_CALCULATED_PARAMETER, CA_INPUT, CA_OUTPUT, CA_LOCAL } Causality;

/* One model variable: where it lives in ModelData and which values it accepts. */
typedef struct {
    unsigned vr;
    const char *name;
    const char *unit;
    VarType type;
    Causality causality;
    int tunable;       /* parameters only: may change after initialisation */
    int has_min, has_max;
    double min, max;   /* inclusive limits, checked on every set */
    int positive;      /* value must be > 0 (strict), checked on every set */
    size_t offset;     /* offsetof(ModelData, field); (size_t)-1 for time */
} VarDef;

#include "model_vars.h" /* generated: ModelData, value references, MODEL_VARS, N_MODEL_VARS */
#include "model.h"      /* the plant's internal state: ModelState */

typedef enum {
    PH_INSTANTIATED,
    PH_INITIALIZATION,
    PH_STEP,
    PH_EVENT,
    PH_TERMINATED,
    PH_ERROR
} Phase;

typedef struct ModelInstance ModelInstance;

typedef void (*LogSink)(ModelInstance *m, Status status, const char *category, const char *message);

struct ModelInstance {
    char *instance_name;
    int logging_on;
    LogSink log_sink;         /* set by the wrapper: forwards to the importer's logger */
    void *env;                /* importer's environment pointer */
    const void *callbacks;    /* FMI 2: the importer's callback struct */
    void (*log_fn)(void);     /* FMI 3: the importer's log function (cast back before the call) */
    Phase phase;
    double start_time;
    double time;              /* current communication point [s], as given by the importer */
    int early_return_allowed; /* FMI 3 only */
    int event_mode_used;      /* FMI 3 only */
    int outputs_stale;        /* an input changed since the outputs were last computed */
    ModelData v;              /* all variables (generated from model.toml) */
    ModelState s;             /* internal state of the plant */
};

/* Snapshot for get/set FMU state. */
typedef struct {
    Phase phase;
    double time;
    ModelData v;
    ModelState s;
} ModelSnapshot;

/* -- shared helpers (cosim_fmu.c) ------------------------------------------------------------ */
ModelInstance *cf_new(const char *instance_name);
void cf_free(ModelInstance *m);
void cf_defaults(ModelInstance *m);
void cf_log(ModelInstance *m, Status status, const char *category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
const VarDef *cf_var(ModelInstance *m, unsigned vr, VarType type, const char *fn);
Status cf_get(ModelInstance *m, VarType type, const unsigned *vr, size_t n, void *values, const char *fn);
Status cf_set(ModelInstance *m, VarType type, const unsigned *vr, size_t n, const void *values, const char *fn);
Status cf_check_all(ModelInstance *m);
Status cf_exit_init(ModelInstance *m);
Status cf_do_step(ModelInstance *m, double t_comm, double h, double *t_reached, int *event);
Status cf_event_indicators(ModelInstance *m, double *z, size_t n);
int cf_phase_allows(ModelInstance *m, const char *fn, int allowed_mask);
#define PH_MASK(p) (1 << (p))

/* -- the plant model (model.c) -------------------------------------------------------------- */
/* Initial internal state, after the parameters are final (exit initialisation mode). */
Status model_init(ModelInstance *m);
/* Extra checks across variables (cf_check_all has already checked each value's range). */
Status model_check(ModelInstance *m);
/* Compute outputs at m->time from the state and the current inputs. */
void model_outputs(ModelInstance *m);
/* Advance from m->time to t_end [s]. May stop early at an internal event (sets *t_reached < t_end
 * and *event = 1) when m->early_return_allowed; otherwise it handles events internally. */
Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event);
/* Event mode (FMI 3): update discrete states at m->time; *again = 1 asks for another iteration. */
Status model_event_update(ModelInstance *m, int *again);
/* Event indicator values at m->time (N_EVENT_INDICATORS of them). */
void model_event_indicators(ModelInstance *m, double *z);

#endif
