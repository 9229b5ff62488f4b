/* FMI 3.0 model exchange, every model kind: no continuous states; each model sample is a time
   event (core.h), the force between events a direct function of the current input. */
#define ME_ONLY(m) \
    if (!(m)->core.me) return fail3((m), "model exchange: not this FMU's mode")

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token,
                                          fmi3String resources, fmi3Boolean visible,
                                          fmi3Boolean logging_on, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback log_message) {
    (void)name; (void)resources; (void)visible;
    return new_instance(token, logging_on, env, log_message, 1);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean no_prior,
                                       fmi3Boolean *enter_event, fmi3Boolean *terminate) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    *enter_event = fmi3False;
    *terminate = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    m->core.t_now = t;
    m->core.pending_valid = 0;
    return fmi3OK;
}

static fmi3Status no_states(Instance *m, size_t n) {
    return n ? fail3(m, "model exchange: this FMU has no continuous states") : fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx) {
    (void)x;
    return no_states((Instance *)c, nx);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx) {
    (void)x;
    return no_states((Instance *)c, nx);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx) {
    (void)dx;
    return no_states((Instance *)c, nx);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 ind[], size_t ni) {
    (void)ind;
    return ni ? fail3((Instance *)c, "model exchange: this FMU has no event indicators") : fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) {
    (void)c;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) {
    (void)c;
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominal[], size_t nx) {
    (void)nominal;
    return no_states((Instance *)c, nx);
}
