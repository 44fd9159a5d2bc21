/*
 * The FMI 3.0 functions the FMI 3.0 test FMUs (msd3.c, types3.c) share verbatim:
 * structure queries, saved states (a state is a malloc'd copy of ModelData, serialized
 * as its bytes), and the derivative, clock, model-exchange and step-mode functions these
 * co-simulation models refuse or answer trivially.
 *
 * A model source includes it after defining ModelData, Instance (with a `ModelData d`
 * member) and `static fmi3Status refuse(Instance *in, const char *why)`.
 */
#ifndef DSMCOSIM_FMI3_CS_COMMON_H
#define DSMCOSIM_FMI3_CS_COMMON_H

/* ---- Structure ---- */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *nDependencies) {
    return refuse((Instance *)instance, "no dependency information at run time");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    return refuse((Instance *)instance, "no dependency information at run time");
}

/* ---- Saved states: a state is a malloc'd copy of ModelData ---- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    Instance *in = (Instance *)instance;
    ModelData *copy;
    if (in == NULL || state == NULL) return fmi3Error;
    copy = (ModelData *)*state;
    if (copy == NULL) copy = (ModelData *)malloc(sizeof(ModelData));
    if (copy == NULL) return refuse(in, "out of memory");
    *copy = in->d;
    *state = copy;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    Instance *in = (Instance *)instance;
    if (in == NULL || state == NULL) return fmi3Error;
    in->d = *(const ModelData *)state;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    if (instance == NULL || state == NULL) return fmi3Error;
    free(*state);
    *state = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    if (instance == NULL || size == NULL) return fmi3Error;
    *size = sizeof(ModelData);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[],
                                 size_t size) {
    Instance *in = (Instance *)instance;
    if (in == NULL || state == NULL || bytes == NULL) return fmi3Error;
    if (size != sizeof(ModelData)) return refuse(in, "wrong buffer size for a state");
    memcpy(bytes, state, sizeof(ModelData));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size,
                                   fmi3FMUState *state) {
    Instance *in = (Instance *)instance;
    ModelData *copy;
    if (in == NULL || bytes == NULL || state == NULL) return fmi3Error;
    if (size != sizeof(ModelData)) return refuse(in, "serialized state has the wrong size");
    copy = (ModelData *)*state;
    if (copy == NULL) copy = (ModelData *)malloc(sizeof(ModelData));
    if (copy == NULL) return refuse(in, "out of memory");
    memcpy(copy, bytes, sizeof(ModelData));
    *state = copy;
    return fmi3OK;
}

/* ---- Derivatives ---- */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    return refuse((Instance *)instance, "no directional derivatives");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    return refuse((Instance *)instance, "no adjoint derivatives");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    return refuse((Instance *)instance, "no output derivatives");
}

/* ---- Clocks ---- */

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    return refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return refuse((Instance *)instance, "no discrete states");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    return refuse((Instance *)instance, "no event mode");
}

/* ---- Model exchange: not this FMU's interface ---- */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    return refuse((Instance *)instance, "co-simulation only");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    return refuse((Instance *)instance, "co-simulation only");
}

/* ---- Co-simulation ---- */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "no event mode: step mode follows initialization");
}


#endif
