/* FMI 3.0 functions this FMU does not provide (scheduled execution, clocks, integer and
   binary types, FMU state, directional derivatives): each reports an error (an importer
   binds every function of the standard when it loads the binary). */
fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn; (void)instanceEnvironment; (void)logMessage; (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    return NULL;
}
fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values;
    return fmi3Error;
}
fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)values;
    return fmi3Error;
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
    (void)instance; (void)FMUState; (void)size;
    return fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    (void)instance; (void)FMUState; (void)serializedState; (void)size;
    return fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState* FMUState) {
    (void)instance; (void)serializedState; (void)size; (void)FMUState;
    return fmi3Error;
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)instance; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity;
    return fmi3Error;
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)instance; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity;
    return fmi3Error;
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    (void)instance;
    return fmi3Error;
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    (void)instance;
    return fmi3Error;
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers;
    return fmi3Error;
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers;
    return fmi3Error;
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)shifts;
    return fmi3Error;
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)intervals;
    return fmi3Error;
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)shifts;
    return fmi3Error;
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fmi3Error;
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    (void)instance;
    return fmi3Error;
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) {
    (void)instance; (void)clockReference; (void)activationTime;
    return fmi3Error;
}
