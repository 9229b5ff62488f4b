/* FMI 2.0 functions this co-simulation FMU does not provide (model exchange): each reports
   an error (an importer may bind every function of the standard when it loads the binary). */
fmi2Status fmi2EnterEventMode(fmi2Component c) {
    (void)c;
    return fmi2Error;
}
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* fmi2eventInfo) {
    (void)c; (void)fmi2eventInfo;
    return fmi2Error;
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    (void)c;
    return fmi2Error;
}
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint, fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
    (void)c; (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return fmi2Error;
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)c; (void)time;
    return fmi2Error;
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)c; (void)x; (void)nx;
    return fmi2Error;
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    (void)c; (void)derivatives; (void)nx;
    return fmi2Error;
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)c; (void)eventIndicators; (void)ni;
    return fmi2Error;
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)c; (void)x; (void)nx;
    return fmi2Error;
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)c; (void)x_nominal; (void)nx;
    return fmi2Error;
}
