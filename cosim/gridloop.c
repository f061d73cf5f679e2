/* The master's sampled grid in C: one call steps an FMU over a row of grid instants and reads its
 * recorded outputs after each step, straight into the master's sample blocks (cosim/gridloop.py).
 *
 * What it saves is the Python around each doStep (the loop, ctypes' argument handling of one doStep
 * and one getter call per FMI type), not C: the FMU's functions are called exactly as the Python loop
 * calls them, with the same arguments (t_s = ticks / per_second, h_s = (t - now) / per_second: both
 * operands exact below 2^53, IEEE division correctly rounded, so the same doubles as Python's
 * int / int), in the same order, so the results are bit-identical. Time stays in integer ticks;
 * doubles are made only for the doStep call (the FMI boundary).
 *
 * A step whose outcome needs the master (a status above Warning, a terminate request, an early
 * return, an event of an FMU in event mode) ends the row: that step is done but not sampled, its
 * outcome is left in the out-arguments and the caller finishes it as its Python path would. A getter
 * failing ends the row too, with *read_failed set (the caller reads again and reports the failure).
 *
 * The FMI types come from fmpy's copy of the FMI headers. */
#include <stddef.h>
#include <stdint.h>

#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

/* One FMI getter call of a sample (one per FMI type), reading into row r at row0 + r * stride. */
typedef struct {
    void *get;   /* fmi2GetReal/Integer/Boolean or fmi3GetFloat64/Int32/... */
    const void *vrs;
    size_t nvr;
    char *row0;
    ptrdiff_t stride;
} CosimGetter;

/* The getters share their instance, value references and a buffer; only the element type differs,
 * which is a pointer at the ABI: called through one type. */
typedef fmi2Status Get2(fmi2Component, const fmi2ValueReference[], size_t, void *);
typedef fmi3Status Get3(fmi3Instance, const fmi3ValueReference[], size_t, void *, size_t);

/* Steps from tick t_now to t0 + (k + j) * period for j = 0 .. n-1, each step followed by the getters
 * into row (row + j) and times[row + j] = its tick. Returns how many steps were done and sampled
 * (n, or fewer where a step needs the caller: see above). */
int cosim_grid_fmi2(fmi2DoStepTYPE *do_step, fmi2Component component, int64_t t_now, int64_t t0,
                    int64_t period, int64_t k, int n, double per_second, const CosimGetter *getters,
                    int n_getters, int64_t *times, int row, int *status, int *read_failed) {
    int j, g;
    *read_failed = 0;
    for (j = 0; j < n; j++) {
        const int64_t t = t0 + (k + j) * period;
        *status = do_step(component, (double)t_now / per_second, (double)(t - t_now) / per_second, fmi2True);
        if (*status > fmi2Warning) {
            return j;
        }
        t_now = t;
        for (g = 0; g < n_getters; g++) {
            const CosimGetter *c = &getters[g];
            if (((Get2 *)c->get)(component, c->vrs, c->nvr, c->row0 + (ptrdiff_t)(row + j) * c->stride) >
                fmi2Warning) {
                *read_failed = 1;
                return j;
            }
        }
        times[row + j] = t;
    }
    return n;
}

int cosim_grid_fmi3(fmi3DoStepTYPE *do_step, fmi3Instance instance, int64_t t_now, int64_t t0,
                    int64_t period, int64_t k, int n, double per_second, int event_mode,
                    const CosimGetter *getters, int n_getters, int64_t *times, int row, int *status,
                    int *read_failed, fmi3Boolean *event, fmi3Boolean *terminate, fmi3Boolean *early,
                    fmi3Float64 *last) {
    int j, g;
    *read_failed = 0;
    for (j = 0; j < n; j++) {
        const int64_t t = t0 + (k + j) * period;
        *status = do_step(instance, (double)t_now / per_second, (double)(t - t_now) / per_second, fmi3True,
                          event, terminate, early, last);
        if (*status > fmi3Warning || *terminate || *early || (event_mode && *event)) {
            return j;
        }
        t_now = t;
        for (g = 0; g < n_getters; g++) {
            const CosimGetter *c = &getters[g];
            if (((Get3 *)c->get)(instance, c->vrs, c->nvr, c->row0 + (ptrdiff_t)(row + j) * c->stride, c->nvr) >
                fmi3Warning) {
                *read_failed = 1;
                return j;
            }
        }
        times[row + j] = t;
    }
    return n;
}
