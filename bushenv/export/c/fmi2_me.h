/* FMI 2.0 model exchange, for ODE models (MODEL_HAS_RHS; Bouc-Wen): the importer integrates
   the states y, w, z1, z2 of seed 002 eqs. 1-4 with its own solver. A recurrence model (linear,
   nn, hybrid) has no states to hand over: these functions report an error for it. */
#define ME_ONLY(m) \
    if (!MODEL_HAS_RHS || !(m)->core.me) return fail2((m), "model exchange: not this FMU's mode")

static fmi2Status me_array(Instance *m, size_t n, size_t want) {
    if (n != want) return fail2(m, "model exchange: wrong number of states or indicators");
    return fmi2OK;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *e) {
    (void)c;
    e->newDiscreteStatesNeeded = fmi2False;
    e->terminateSimulation = fmi2False;
    e->nominalsOfContinuousStatesChanged = fmi2False;
    e->valuesOfContinuousStatesChanged = fmi2False;
    e->nextEventTimeDefined = fmi2False;
    e->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean no_prior,
                                       fmi2Boolean *enter_event, fmi2Boolean *terminate) {
    (void)no_prior;
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    core_me_completed(&m->core);
    *enter_event = fmi2False;
    *terminate = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    m->core.t_now = t;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi2Error;
    for (int i = 0; i < 4; i++) m->core.q[i] = x[i];
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi2Error;
    for (int i = 0; i < 4; i++) x[i] = m->core.q[i];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi2Error;
    model_rhs(m->core.x_now, m->core.v_now, m->core.q, dx);
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ind[], size_t ni) {
    Instance *m = (Instance *)c;
    if (me_array(m, ni, m->core.me ? N_INDICATORS : 0)) return fmi2Error;
    if (ni) var_indicators(&m->core, ind);
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real nominal[], size_t nx) {
    Instance *m = (Instance *)c;
    ME_ONLY(m);
    if (me_array(m, nx, 4)) return fmi2Error;
    for (int i = 0; i < 4; i++) nominal[i] = 1e-3; /* y, w, z in m: bushing strokes are mm */
    return fmi2OK;
}
