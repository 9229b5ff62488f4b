/* FMI 2.0 model exchange, every model kind: no continuous states; each model sample is a time
   event (core.h), the force between events a direct function of the current input. */
#define ME_ONLY(m) \
    if (!(m)->core.me) return fail2((m), "model exchange: not this FMU's mode")

fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (core_me_event(&m->core)) return fail2(m, m->core.message);
    e->newDiscreteStatesNeeded = fmi2False;
    e->terminateSimulation = fmi2False;
    e->nominalsOfContinuousStatesChanged = fmi2False;
    e->valuesOfContinuousStatesChanged = fmi2False;
    e->nextEventTimeDefined = fmi2True;
    e->nextEventTime = core_me_next_event(&m->core);
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean no_prior,
                                       fmi2Boolean *enter_event, fmi2Boolean *terminate) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    *enter_event = fmi2False;
    *terminate = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    m->core.t_now = t;
    m->core.pending_valid = 0;
    return fmi2OK;
}

static fmi2Status no_states(Instance *m, size_t n) {
    return n ? fail2(m, "model exchange: this FMU has no continuous states") : fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x;
    return no_states((Instance *)c, nx);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x;
    return no_states((Instance *)c, nx);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    (void)dx;
    return no_states((Instance *)c, nx);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ind[], size_t ni) {
    (void)ind;
    return ni ? fail2((Instance *)c, "model exchange: this FMU has no event indicators") : fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nominal[], size_t nx) {
    (void)nominal;
    return no_states((Instance *)c, nx);
}
