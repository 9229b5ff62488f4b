/* FMI 3.0 interface of a bushenv bushing FMU (model.h generated, core.h shared): co-simulation,
   and model exchange (fmi3_me.h). Functions of scheduled execution and of types
   this FMU has none of are in fmi3_stubs.h: they report an error. */
#include <stdlib.h>
#include "fmi3Functions.h"
#include "model.h"
#include "core.h"
#include "variables.h"

typedef struct {
    Core core;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log_message;
    int logging_on;
} Instance;

static void log_fmi3(void *env, int warning, const char *message) {
    Instance *m = (Instance *)env;
    if (!m->log_message || (!warning && !m->logging_on)) return;
    m->log_message(m->env, warning ? fmi3Warning : fmi3OK,
                   warning ? "logStatusWarning" : "logAll", message);
}

static fmi3Status fail3(Instance *m, const char *message) {
    if (m && m->log_message) m->log_message(m->env, fmi3Error, "logStatusError", message);
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cat[]) {
    (void)n; (void)cat;
    ((Instance *)c)->logging_on = on;
    return fmi3OK;
}

static Instance *new_instance(fmi3String token, fmi3Boolean logging_on,
                              fmi3InstanceEnvironment env, fmi3LogMessageCallback log_message,
                              int me) {
    if (!token || strcmp(token, FMU_TOKEN) != 0) {
        if (log_message)
            log_message(env, fmi3Error, "logStatusError",
                        "instantiation token does not match this binary's " FMU_TOKEN);
        return NULL;
    }
    Instance *m = (Instance *)calloc(1, sizeof(Instance));
    if (!m) return NULL;
    m->env = env;
    m->log_message = log_message;
    m->logging_on = logging_on;
    core_reset(&m->core, 0.0);
    m->core.me = me;
    m->core.log = log_fmi3;
    m->core.log_env = m;
    return m;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
    fmi3Boolean logging_on, fmi3Boolean event_mode_used, fmi3Boolean early_return_allowed,
    const fmi3ValueReference required[], size_t n_required, fmi3InstanceEnvironment env,
    fmi3LogMessageCallback log_message, fmi3IntermediateUpdateCallback intermediate) {
    (void)name; (void)resources; (void)visible; (void)event_mode_used;
    (void)early_return_allowed; (void)required; (void)n_required; (void)intermediate;
    return new_instance(token, logging_on, env, log_message, 0);
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tol_defined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stop_defined,
                                       fmi3Float64 stop) {
    (void)tol_defined; (void)tol; (void)stop_defined; (void)stop;
    Instance *m = (Instance *)c;
    core_restart(&m->core, start);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    Instance *m = (Instance *)c;
    m->core.started = 1;
    core_log_certificate(&m->core);
    return fmi3OK;
}
fmi3Status fmi3EnterEventMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3EnterStepMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3Terminate(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3Reset(fmi3Instance c) {
    Instance *m = (Instance *)c;
    int me = m->core.me;
    core_reset(&m->core, 0.0);
    m->core.me = me;
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *update, fmi3Boolean *terminate,
                                    fmi3Boolean *nominals, fmi3Boolean *values,
                                    fmi3Boolean *next_defined, fmi3Float64 *next) {
    Instance *m = (Instance *)c;
    *update = *terminate = *nominals = *values = *next_defined = fmi3False;
    *next = 0.0;
    if (!m->core.me) return fmi3OK;
    if (core_me_event(&m->core)) return fail3(m, m->core.message);
    *next_defined = fmi3True; /* model exchange: the next sample is the next time event */
    *next = core_me_next_event(&m->core);
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                          fmi3Float64 v[], size_t nv) {
    Instance *m = (Instance *)c;
    if (nv < n) return fail3(m, "fmi3GetFloat64: fewer values than value references");
    for (size_t i = 0; i < n; i++) {
        int r = var_get_real(&m->core, vr[i], &v[i]);
        if (r < 0) return fail3(m, m->core.message);
        if (r > 0) return fail3(m, "fmi3GetFloat64: unknown value reference");
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                          const fmi3Float64 v[], size_t nv) {
    Instance *m = (Instance *)c;
    if (nv < n) return fail3(m, "fmi3SetFloat64: fewer values than value references");
    for (size_t i = 0; i < n; i++)
        if (var_set_real(&m->core, vr[i], v[i]))
            return fail3(m, "fmi3SetFloat64: only the inputs can be set");
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                          fmi3Boolean v[], size_t nv) {
    Instance *m = (Instance *)c;
    if (nv < n) return fail3(m, "fmi3GetBoolean: fewer values than value references");
    for (size_t i = 0; i < n; i++) {
        int b, r = var_get_boolean(&m->core, vr[i], &b);
        if (r < 0) return fail3(m, m->core.message);
        if (r > 0) return fail3(m, "fmi3GetBoolean: unknown value reference");
        v[i] = b ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                          const fmi3Boolean v[], size_t nv) {
    (void)vr; (void)v; (void)nv;
    return n ? fail3((Instance *)c, "fmi3SetBoolean: only the inputs can be set") : fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                         fmi3String v[], size_t nv) {
    Instance *m = (Instance *)c;
    if (nv < n) return fail3(m, "fmi3GetString: fewer values than value references");
    for (size_t i = 0; i < n; i++) {
        v[i] = var_get_string(vr[i]);
        if (!v[i]) return fail3(m, "fmi3GetString: unknown value reference");
    }
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                         const fmi3String v[], size_t nv) {
    (void)vr; (void)v; (void)nv;
    return n ? fail3((Instance *)c, "fmi3SetString: the strings are constants") : fmi3OK;
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr,
                                               size_t *n) {
    (void)c; (void)vr;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                       size_t ed[], fmi3ValueReference ind[], size_t ei[],
                                       fmi3DependencyKind kinds[], size_t n) {
    (void)dependent; (void)ed; (void)ind; (void)ei; (void)kinds; (void)n;
    return fail3((Instance *)c, "fmi3GetVariableDependencies: see modelDescription.xml");
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) {
    (void)s;
    return fail3((Instance *)c, "fmi3GetFMUState: not supported");
}
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) {
    (void)s;
    return fail3((Instance *)c, "fmi3SetFMUState: not supported");
}
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) {
    (void)s;
    return fail3((Instance *)c, "fmi3FreeFMUState: not supported");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t n,
                                    const fmi3Int32 orders[], fmi3Float64 v[], size_t nv) {
    (void)vr; (void)orders; (void)v; (void)nv;
    return n ? fail3((Instance *)c, "fmi3GetOutputDerivatives: not provided") : fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                      fmi3Boolean *event, fmi3Boolean *terminate, fmi3Boolean *early,
                      fmi3Float64 *last) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    *event = *terminate = *early = fmi3False;
    if (!(h >= 0.0)) return fail3(m, "fmi3DoStep: negative communication step");
    if (core_do_step(&m->core, t, h)) {
        *last = t;
        return fail3(m, m->core.message);
    }
    *last = t + h;
    return fmi3OK;
}

#include "fmi3_me.h"
#include "fmi3_stubs.h"
