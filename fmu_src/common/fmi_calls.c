/* The entry check of every FMI function: the state table of fmi_calls.h. */
#include "cosim_fmu.h"

typedef struct {
    const char *name;
    unsigned char allowed[N_PHASES];
} CallRow;

static const CallRow CALLS[N_FMI_CALLS] = {
#define CALL_ROW(name, i, n, s, e, t, r, f)                                                                      \
    {#name,                                                                                                      \
     {[PH_INSTANTIATED] = i, [PH_INITIALIZATION] = n, [PH_STEP] = s, [PH_EVENT] = e, [PH_TERMINATED] = t,      \
      [PH_ERROR] = r, [PH_FATAL] = f}},
    FMI_CALLS(CALL_ROW)
#undef CALL_ROW
};

static const char *const PHASE_NAME[N_PHASES] = {
    [PH_INSTANTIATED] = "instantiated",
    [PH_INITIALIZATION] = "initialization mode",
    [PH_STEP] = "step mode",
    [PH_EVENT] = "event mode",
    [PH_TERMINATED] = "terminated",
    [PH_ERROR] = "the error state (after an earlier error)",
    [PH_FATAL] = "the fatal state (after an earlier fatal error)",
};

const char *cf_call_name(FmiCall call) { return CALLS[call].name; }

int cf_enter(ModelInstance *m, FmiCall call) {
    if (m == NULL) {
        return 0;
    }
    if (CALLS[call].allowed[m->phase]) {
        return 1;
    }
    cf_log(m, ST_ERROR, "logStatusError", "%s must not be called in %s", CALLS[call].name, PHASE_NAME[m->phase]);
    cf_result(m, ST_ERROR);
    return 0;
}
