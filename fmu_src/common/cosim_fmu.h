/* cosim plant FMUs: the interface between a plant model and the FMI 2.0 / 3.0 wrappers.
 *
 * A plant folder holds model.toml (its variables, from which the build generates model_vars.h,
 * model_vars.c and both modelDescription.xml files), model.h (its internal state) and model.c
 * (the functions declared at the end of this header). The wrappers fmi2_cs.c and fmi3_cs.c turn
 * those functions into the FMI API; every FMI function first asks the state table (fmi_calls.h)
 * whether the instance's state allows the call. Every instance owns all of its data: there is no
 * global state, so any number of instances can live in one process.
 */
#ifndef COSIM_FMU_H
#define COSIM_FMU_H

#include <stddef.h>
#include <stdint.h>

typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } Status;

/* The FMI 3.0 variable types. FMI 2.0 has Real (VT_FLOAT64), Integer (VT_INT32), Boolean, String
 * and Enumeration; the other types are FMI 3.0 only. A Boolean is stored as int, an Enumeration as
 * int64_t (FMI 3.0 reads it with fmi3GetInt64, FMI 2.0 with fmi2GetInteger), a String as a char
 * array of CF_STRING_CAPACITY bytes, a Binary as a CfBinary. VT_BOOL_C is not a storage type: it is
 * how fmi3GetBoolean / fmi3SetBoolean pass their values (C bool, where FMI 2.0 passes int). */
typedef enum {
    VT_FLOAT64,
    VT_INT32,
    VT_BOOL,
    VT_FLOAT32,
    VT_INT8,
    VT_UINT8,
    VT_INT16,
    VT_UINT16,
    VT_UINT32,
    VT_INT64,
    VT_UINT64,
    VT_STRING,
    VT_BINARY,
    VT_ENUM,
    VT_BOOL_C,
    N_VAR_TYPES
} VarType;

/* Room for one String value (terminating NUL included) and one Binary value: longer values are
 * refused by the setter with a message. Both live inside ModelData, so FMU state snapshots stay
 * plain copies. */
#define CF_STRING_CAPACITY 256
#define CF_BINARY_CAPACITY 256

typedef struct {
    size_t size;
    unsigned char data[CF_BINARY_CAPACITY];
} CfBinary;

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
    size_t n;          /* elements: 1 for a scalar, the product of the dimensions for an array
                        * (stored flat in row-major order, as FMI 3.0 passes them) */
} VarDef;

#include "model_vars.h" /* generated: ModelData, value references, MODEL_VARS, N_MODEL_VARS */
#include "model.h"      /* the plant's internal state: ModelState */
#include "fmi_calls.h" /* the state table: FmiCall, cf_enter */

/* The state of an instance in the FMI state machines; which calls each allows: fmi_calls.h. */
typedef enum {
    PH_INSTANTIATED,
    PH_INITIALIZATION,
    PH_STEP,
    PH_EVENT,
    PH_TERMINATED,
    PH_ERROR,
    PH_FATAL,
    N_PHASES
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
    int terminate_requested;  /* the model asked to end the simulation (model_step or model_event_update
                               * set it): FMI 3.0 reports terminateSimulation, FMI 2.0 returns fmi2Discard
                               * with fmi2Terminated; a later doStep is refused */
    ModelData v;              /* all variables (generated from model.toml) */
    ModelState s;             /* internal state of the plant */
};

/* -- shared helpers (cosim_fmu.c) ------------------------------------------------------------ */
/* The FMI wrappers call these after their entry check (cf_enter): none of them looks at the
 * instance's state. `call` names the FMI function in messages. The wrappers pass every status they
 * return through cf_result. */
ModelInstance *cf_new(const char *instance_name);
void cf_free(ModelInstance *m);
void cf_defaults(ModelInstance *m);
void cf_log(ModelInstance *m, Status status, const char *category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
/* The state after a call that returns `status`: the error (fatal) state for ST_ERROR (ST_FATAL). */
Status cf_result(ModelInstance *m, Status status);
Status cf_null_argument(ModelInstance *m, FmiCall call, const char *argument);
/* An error: for FMI functions these FMUs do not offer. */
Status cf_unsupported(ModelInstance *m, FmiCall call);
/* Fine for n == 0, an error otherwise: for functions that reach no variable (clocks). */
Status cf_no_vars(ModelInstance *m, FmiCall call, size_t n);
/* Get or set the variables vr[0..nvr) through an FMI getter/setter whose values array holds elements
 * of `type` (a String: const char *); nValues is the length of that array, the sum of the variables'
 * element counts (FMI 2.0 passes nvr: it has scalars only). A variable of another type, an unknown
 * value reference or a wrong nValues is an error with a message naming it. */
Status cf_get(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t nvr, void *values,
              size_t nValues);
Status cf_set(ModelInstance *m, FmiCall call, VarType type, const unsigned *vr, size_t nvr, const void *values,
              size_t nValues);
/* fmi3GetBinary / fmi3SetBinary: sizes and pointers of each element. */
Status cf_get_binary(ModelInstance *m, FmiCall call, const unsigned *vr, size_t nvr, size_t *sizes,
                     const unsigned char **values, size_t nValues);
Status cf_set_binary(ModelInstance *m, FmiCall call, const unsigned *vr, size_t nvr, const size_t *sizes,
                     const unsigned char *const *values, size_t nValues);
Status cf_exit_init(ModelInstance *m);
Status cf_do_step(ModelInstance *m, FmiCall call, double t_comm, double h, double *t_reached, int *event);
Status cf_event_indicators(ModelInstance *m, FmiCall call, double *z, size_t n);
/* FMU state: a snapshot is a plain copy of the instance's state, time and variables. */
Status cf_state_get(ModelInstance *m, FmiCall call, void **state);
Status cf_state_set(ModelInstance *m, FmiCall call, const void *state);
Status cf_state_free(ModelInstance *m, FmiCall call, void **state);
Status cf_state_size(ModelInstance *m, FmiCall call, size_t *size);
Status cf_state_serialize(ModelInstance *m, FmiCall call, const void *state, unsigned char *bytes, size_t size);
Status cf_state_deserialize(ModelInstance *m, FmiCall call, const unsigned char *bytes, size_t size, void **state);

/* -- the plant model (model.c) -------------------------------------------------------------- */
/* Initial internal state, after the parameters are final (exit initialisation mode). */
Status model_init(ModelInstance *m);
/* Extra checks across variables (each value's own range is already checked on every set and at exit
 * initialisation mode). */
Status model_check(ModelInstance *m);
/* Compute outputs at m->time from the state and the current inputs. */
void model_outputs(ModelInstance *m);
/* Advance from m->time to t_end [s]. May stop early at an internal event (sets *t_reached < t_end
 * and *event = 1) when m->early_return_allowed; otherwise it handles events internally. A model that
 * asks to end the simulation stops at that instant (*t_reached) and sets m->terminate_requested. */
Status model_step(ModelInstance *m, double t_end, double *t_reached, int *event);
/* Event mode (FMI 3): update discrete states at m->time; *again = 1 asks for another iteration
 * (m->terminate_requested = 1 asks to end the simulation).
 * (A plant without events takes this and model_event_indicators from no_events.c.) */
Status model_event_update(ModelInstance *m, int *again);
/* Event indicator values at m->time (N_EVENT_INDICATORS of them). */
void model_event_indicators(ModelInstance *m, double *z);

#endif
