/* FMI 2.0 interface of a bushenv bushing FMU (model.h generated, core.h shared): co-simulation,
   and model exchange (fmi2_me.h). */
#include <stdlib.h>
#include "fmi2Functions.h"
#include "model.h"
#include "core.h"
#include "variables.h"

typedef struct {
    Core core;
    fmi2CallbackFunctions cb;
    char name[128]; /* a copy: the importer's string need not outlive fmi2Instantiate */
    int logging_on;
    int initialised;
} Instance;

/* The logger's message is a printf format: importers that do not format it (a Python
   callback) would show "%s", so the text itself is passed, its '%' doubled. */
static void send2(Instance *m, fmi2Status status, const char *category, const char *message) {
    char text[1024];
    size_t j = 0;
    for (size_t i = 0; message[i] && j + 2 < sizeof text; i++) {
        if (message[i] == '%') text[j++] = '%';
        text[j++] = message[i];
    }
    text[j] = 0;
    m->cb.logger(m->cb.componentEnvironment, m->name, status, category, text);
}

static void log_fmi2(void *env, int warning, const char *message) {
    Instance *m = (Instance *)env;
    if (!warning && !m->logging_on) return;
    send2(m, warning ? fmi2Warning : fmi2OK, warning ? "logStatusWarning" : "logAll", message);
}

static fmi2Status fail2(Instance *m, const char *message) {
    if (m && m->cb.logger) send2(m, fmi2Error, "logStatusError", message);
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)n; (void)cat;
    ((Instance *)c)->logging_on = on;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging_on) {
    (void)resources; (void)visible;
    if (!cb || !cb->logger) return NULL;
    if (!guid || strcmp(guid, FMU_TOKEN) != 0) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError",
                   "GUID %s does not match this binary's %s", guid ? guid : "(null)", FMU_TOKEN);
        return NULL;
    }
    Instance *m = (Instance *)calloc(1, sizeof(Instance));
    if (!m) return NULL;
    m->cb = *cb;
    snprintf(m->name, sizeof m->name, "%s", name ? name : "");
    m->logging_on = logging_on;
    core_reset(&m->core, 0.0);
    m->core.me = type == fmi2ModelExchange;
    m->core.log = log_fmi2;
    m->core.log_env = m;
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tol_defined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    (void)tol_defined; (void)tol; (void)stop_defined; (void)stop;
    Instance *m = (Instance *)c;
    core_restart(&m->core, start);
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *m = (Instance *)c;
    m->initialised = 1;
    m->core.started = 1;
    core_log_certificate(&m->core);
    return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) {
    Instance *m = (Instance *)c;
    int me = m->core.me;
    core_reset(&m->core, 0.0);
    m->core.me = me;
    m->initialised = 0;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Instance *m = (Instance *)c;
    for (size_t i = 0; i < n; i++) {
        int r = var_get_real(&m->core, vr[i], &v[i]);
        if (r < 0) return fail2(m, m->core.message);
        if (r > 0) return fail2(m, "fmi2GetReal: unknown value reference");
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) {
    (void)vr; (void)v;
    return n ? fail2((Instance *)c, "fmi2GetInteger: this FMU has no Integer variables") : fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean v[]) {
    Instance *m = (Instance *)c;
    for (size_t i = 0; i < n; i++) {
        int b, r = var_get_boolean(&m->core, vr[i], &b);
        if (r < 0) return fail2(m, m->core.message);
        if (r > 0) return fail2(m, "fmi2GetBoolean: unknown value reference");
        v[i] = b ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String v[]) {
    for (size_t i = 0; i < n; i++) {
        v[i] = var_get_string(vr[i]);
        if (!v[i]) return fail2((Instance *)c, "fmi2GetString: unknown value reference");
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    Instance *m = (Instance *)c;
    for (size_t i = 0; i < n; i++)
        if (var_set_real(&m->core, vr[i], v[i]))
            return fail2(m, "fmi2SetReal: only the inputs can be set");
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) {
    (void)vr; (void)v;
    return n ? fail2((Instance *)c, "fmi2SetInteger: this FMU has no Integer variables") : fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) {
    (void)vr; (void)v;
    return n ? fail2((Instance *)c, "fmi2SetBoolean: only the inputs can be set") : fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) {
    (void)vr; (void)v;
    return n ? fail2((Instance *)c, "fmi2SetString: the strings are constants") : fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return fail2((Instance *)c, "fmi2GetFMUstate: not supported");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    (void)s;
    return fail2((Instance *)c, "fmi2SetFMUstate: not supported");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    return fail2((Instance *)c, "fmi2FreeFMUstate: not supported");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)s; (void)n;
    return fail2((Instance *)c, "fmi2SerializedFMUstateSize: not supported");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)s; (void)b; (void)n;
    return fail2((Instance *)c, "fmi2SerializeFMUstate: not supported");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n,
                                   fmi2FMUstate *s) {
    (void)s; (void)b; (void)n;
    return fail2((Instance *)c, "fmi2DeSerializeFMUstate: not supported");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fail2((Instance *)c, "fmi2GetDirectionalDerivative: not supported");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    Instance *m = (Instance *)c;
    for (size_t i = 0; i < n; i++) {
        if (order[i] != 1) continue; /* the input is linear between points: higher orders unused */
        int velocity, k;
        if (var_input(vr[i], &velocity, &k))
            return fail2(m, "fmi2SetRealInputDerivatives: not an input");
        core_set_derivative(&m->core, velocity, k, v[i]);
    }
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real v[]) {
    (void)vr; (void)order; (void)v;
    return n ? fail2((Instance *)c, "fmi2GetRealOutputDerivatives: not provided") : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    if (!(h >= 0.0)) return fail2(m, "fmi2DoStep: negative communication step");
    if (core_do_step(&m->core, t, h)) return fail2(m, m->core.message);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return fail2((Instance *)c, "fmi2CancelStep: doStep never runs asynchronously here");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind k, fmi2Status *v) {
    (void)k; (void)v;
    return fail2((Instance *)c, "fmi2GetStatus: doStep never runs asynchronously here");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind k, fmi2Real *v) {
    Instance *m = (Instance *)c;
    if (k == fmi2LastSuccessfulTime) {
        *v = m->core.t_now;
        return fmi2OK;
    }
    return fail2(m, "fmi2GetRealStatus: only fmi2LastSuccessfulTime");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind k, fmi2Integer *v) {
    (void)k; (void)v;
    return fail2((Instance *)c, "fmi2GetIntegerStatus: not provided");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v) {
    if (k == fmi2Terminated) {
        *v = fmi2False;
        return fmi2OK;
    }
    return fail2((Instance *)c, "fmi2GetBooleanStatus: only fmi2Terminated");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind k, fmi2String *v) {
    (void)k; (void)v;
    return fail2((Instance *)c, "fmi2GetStringStatus: not provided");
}

#include "fmi2_me.h"
