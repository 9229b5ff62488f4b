/* FMI 3.0 model exchange, for ODE models (MODEL_HAS_RHS; Bouc-Wen): the importer integrates
   the states y, w, z1, z2 of seed 002 eqs. 1-4 with its own solver. A recurrence model (linear,
   nn, hybrid) has no states to hand over: it cannot be instantiated so. */
#define ME_ONLY(m) \
    if (!MODEL_HAS_RHS || !(m)->core.me) return fail3((m), "model exchange: not this FMU's mode")

static fmi3Status me_array(Instance *m, size_t n, size_t want) {
    if (n != want) return fail3(m, "model exchange: wrong number of states or indicators");
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token,
                                          fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging_on, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback log_message) {
    (void)name; (void)resources; (void)visible;
    if (!MODEL_HAS_RHS) {
        if (log_message)
            log_message(env, fmi3Error, "logStatusError", "this FMU supports co-simulation only");
        return NULL;
    }
    return new_instance(token, logging_on, env, log_message, 1);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean no_prior,
                                       fmi3Boolean *enter_event, fmi3Boolean *terminate) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    core_me_completed(&m->core);
    *enter_event = fmi3False;
    *terminate = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    m->core.t_now = t;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi3Error;
    for (int i = 0; i < 4; i++) m->core.q[i] = x[i];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi3Error;
    for (int i = 0; i < 4; i++) x[i] = m->core.q[i];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi3Error;
    model_rhs(m->core.x_now, m->core.v_now, m->core.q, dx);
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 ind[], size_t ni) {
    Instance *m = (Instance *)c;
    if (me_array(m, ni, m->core.me ? N_INDICATORS : 0)) return fmi3Error;
    if (ni) var_indicators(&m->core, ind);
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) {
    *n = ((Instance *)c)->core.me ? N_INDICATORS : 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) {
    (void)c;
    *n = MODEL_HAS_RHS ? 4 : 0;
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominal[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi3Error;
    for (int i = 0; i < 4; i++) nominal[i] = 1e-3; /* y, w, z in m: bushing strokes are mm */
    return fmi3OK;
}
