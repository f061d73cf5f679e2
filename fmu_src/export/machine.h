/* The C entry point of a machine exported as an FMU (cosim export-fmu).
 *
 * The FMU's simulation is cosim itself, in Python. This layer loads the Python runtime the FMU
 * recorded at export time (resources/cosim/runtime.txt: the shared libpython, PYTHONHOME and the
 * environment's site folders), or uses the interpreter of a Python importer (fmpy) when there is
 * one in the process, then creates the machine through cosim.fmu_export.runtime and forwards the
 * FMI calls to it. Python owns the variable values and their types (one double per value
 * reference); the getters and setters of both FMI versions read and write them here, without a
 * call into Python. When the runtime is missing the instantiation fails with a message that says
 * what is missing and where it was looked for.
 *
 * No Python header is used: the few functions of the CPython stable ABI this needs are looked up
 * with dlsym, so the binary loads in any importer, with or without Python. */
#ifndef COSIM_MACHINE_H
#define COSIM_MACHINE_H

#include <stddef.h>

typedef enum { MS_OK = 0, MS_WARNING = 1, MS_DISCARD = 2, MS_ERROR = 3, MS_FATAL = 4 } MStatus;

/* The instance's state; a set of states is their bitwise or. */
typedef enum {
    PH_INSTANTIATED = 1,
    PH_INITIALIZATION = 2,
    PH_STEP = 4,
    PH_EVENT = 8,
    PH_TERMINATED = 16,
    PH_ERROR = 32
} Phase;

/* The kind byte of a value reference (Python fills the table): its type and causality. */
enum { VK_FLOAT64 = 1, VK_INT32 = 2, VK_BOOLEAN = 3, VK_TYPE = 0x0f, VK_INPUT = 0x10, VK_OUTPUT = 0x20 };

/* What fmi3DoStep / fmi2DoStep report, written by Python after each step. */
enum { SR_LAST_TIME, SR_EVENT, SR_EARLY, SR_TERMINATE, SR_SIZE };

typedef struct Machine Machine;

/* Forwards one message to the importer's logger (FMI 2.0 or 3.0). */
typedef void (*MachineSink)(const Machine *m, MStatus status, const char *category, const char *message);

struct Machine {
    char *name;
    int fmi_version;
    MachineSink sink;
    void *env;              /* FMI 3: instance environment; FMI 2: component environment */
    const void *callbacks;  /* FMI 2: the importer's callback struct */
    void (*log_fn)(void);   /* FMI 3: the importer's log function */
    int logging_on;
    int event_mode_used;    /* FMI 3: the importer uses event mode */
    double start_time, stop_time; /* FMI 2: fmi2SetupExperiment, passed on at fmi2EnterInitializationMode */
    int stop_defined;
    Phase phase;
    void *slave;            /* the Python object (cosim.fmu_export.runtime.Slave) */
    double *values;         /* one value per value reference, owned by Python */
    const unsigned char *kinds;
    size_t n_values;
    const double *step;     /* SR_SIZE values: the last step's results, owned by Python */
};

/* Load the runtime (once per process) and create the machine; NULL after a logged error.
 * `resources` is the FMU's resources folder as a file system path. */
Machine *machine_new(int fmi_version, const char *name, const char *token, const char *resources, MachineSink sink,
                     void *env, const void *callbacks, void (*log_fn)(void), int logging_on, int event_mode_used,
                     int early_return_allowed);
void machine_free(Machine *m);

void machine_log(const Machine *m, MStatus status, const char *category, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* 1 if the instance's state is in `allowed`; else logs "<fn> must not be called in <state>",
 * puts the instance in the error state and returns 0. A NULL instance gives 0. */
int machine_enter(Machine *m, const char *fn, unsigned allowed);
/* The state after a call returning `status`: the error state for MS_ERROR and worse. */
MStatus machine_result(Machine *m, MStatus status);
/* slave.<method>(*args) -> status; `format` is a Py_BuildValue format of a tuple, e.g. "(dd)". */
MStatus machine_call(Machine *m, const char *method, const char *format, ...);
/* Variables: type checks, conversion to and from the double of each value reference. */
MStatus machine_get(Machine *m, const char *fn, int type, const unsigned *vr, size_t n, void *values);
MStatus machine_set(Machine *m, const char *fn, int type, const unsigned *vr, size_t n, const void *values);
/* An error for a function the FMU does not offer. */
MStatus machine_unsupported(Machine *m, const char *fn);

#endif
