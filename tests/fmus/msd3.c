/*
 * Mass-spring-damper, a test FMU for dsmcosim in FMI 3.0 co-simulation form:
 *
 *     m x'' = -k x - c x' + F
 *
 * The same model, parameters and arithmetic as msd.c (FMI 2.0): F is an input held over
 * each communication step, each fmi3DoStep(t, h) integrates with classic RK4 over
 * n = ceil(h / 1e-4) equal substeps, and the outputs are x, v and the acceleration a
 * with the current input. So msd3 and msd stepped alike give the same bits. A state is
 * a copy of ModelData; it serializes as its bytes.
 *
 * FMI 3.0 differs from 2.0 here in: no memory callbacks (the FMU allocates with malloc),
 * a non-variadic log callback, the start and stop times passed to
 * fmi3EnterInitializationMode (no fmi3SetupExperiment), C99 bool for Boolean, and the
 * value count passed to every getter and setter. Every function of the standard is
 * exported (FMPy resolves them all); those this model does not support answer fmi3Error.
 *
 * A test may build it with MSD3_TERMINATE_AT defined (a time [s]): a step that reaches
 * that time then sets terminateSimulation, as an FMU whose model has ended would.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_abi.h"

#define MODEL_TOKEN "{b3f1d6a2-7c4e-4f0a-9e21-5d8c3a6b7f03}"

#include "msd_model.h"

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED } Mode;

typedef struct {
    ModelData d;
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
    Mode mode;
    bool logging;
} Instance;

enum { VR_M, VR_K, VR_C, VR_X0, VR_V0, VR_F, VR_X, VR_V, VR_A, VR_TIME };


/* Logs through the importer: errors always, the rest when logging is on. */
static void log_text(Instance *in, fmi3Status status, const char *category, const char *message) {
    if (in == NULL || in->log == NULL || (!in->logging && status < fmi3Error)) return;
    in->log(in->env, status, category, message);
}

static fmi3Status refuse(Instance *in, const char *what) {
    log_text(in, fmi3Error, "logStatusError", what);
    return fmi3Error;
}


static fmi3Status get_float64(Instance *in, fmi3ValueReference vr, fmi3Float64 *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_M: *value = d->m; break;
    case VR_K: *value = d->k; break;
    case VR_C: *value = d->c; break;
    case VR_X0: *value = d->x0; break;
    case VR_V0: *value = d->v0; break;
    case VR_F: *value = d->F; break;
    case VR_X: *value = d->x; break;
    case VR_V: *value = d->v; break;
    case VR_A: *value = acceleration(d, d->x, d->v); break;
    case VR_TIME: *value = d->time; break;
    default: return refuse(in, "unknown Float64 value reference");
    }
    return fmi3OK;
}

static fmi3Status set_float64(Instance *in, fmi3ValueReference vr, fmi3Float64 value) {
    ModelData *d = &in->d;
    int parameter = vr <= VR_V0;
    if (parameter && in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    switch (vr) {
    case VR_M:
        if (!(value > 0.0)) return refuse(in, "m must be > 0");
        d->m = value;
        break;
    case VR_K: d->k = value; break;
    case VR_C: d->c = value; break;
    case VR_X0: d->x0 = d->x = value; break;
    case VR_V0: d->v0 = d->v = value; break;
    case VR_F: d->F = value; break;
    default: return refuse(in, "only parameters and the input F can be set");
    }
    return fmi3OK;
}

static fmi3Status model_do_step(Instance *in, fmi3Float64 t, fmi3Float64 h) {
    (void)t;
    if (msd_integrate(&in->d, h) != 0) return refuse(in, "the state is no longer finite");
    return fmi3OK;
}

/* ---- Inquiry, logging, life cycle ---- */

const char *fmi3GetVersion(void) { return "3.0"; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    in->logging = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    return NULL; /* co-simulation only */
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    Instance *in;
    if (instanceName == NULL || instantiationToken == NULL ||
        strcmp(instantiationToken, MODEL_TOKEN) != 0)
        return NULL;
    in = (Instance *)calloc(1, sizeof(Instance));
    if (in == NULL) return NULL;
    in->log = logMessage;
    in->env = instanceEnvironment;
    in->logging = loggingOn;
    in->mode = MODE_INSTANTIATED;
    model_defaults(&in->d);
    /* This FMU has no event mode; an importer asking for it gets an error and no instance. */
    if (eventModeUsed) {
        refuse(in, "event mode is not supported (canHandleEvents is not declared)");
        free(in);
        return NULL;
    }
    log_text(in, fmi3OK, "logEvents", "instantiated");
    return in;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    return NULL; /* co-simulation only */
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

/* ---- Modes ---- */

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    if (in->mode != MODE_INSTANTIATED) return refuse(in, "fmi3EnterInitializationMode twice");
    in->d.time = startTime;
    in->mode = MODE_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    if (in->mode != MODE_INITIALIZATION)
        return refuse(in, "fmi3ExitInitializationMode outside initialization mode");
    in->mode = MODE_STEP; /* without event mode, co-simulation goes straight to step mode */
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "no event mode");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    in->mode = MODE_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    model_defaults(&in->d);
    in->mode = MODE_INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "no structural parameters");
}

/* ---- Values ---- */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    if (nValues != nvr) return refuse(in, "fmi3GetFloat64: one value per (scalar) reference");
    for (size_t i = 0; i < nvr; i++) {
        fmi3Status s = get_float64(in, vr[i], &values[i]);
        if (s != fmi3OK) return s;
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    Instance *in = (Instance *)instance;
    if (in == NULL) return fmi3Error;
    if (nValues != nvr) return refuse(in, "fmi3SetFloat64: one value per (scalar) reference");
    for (size_t i = 0; i < nvr; i++) {
        fmi3Status s = set_float64(in, vr[i], values[i]);
        if (s != fmi3OK) return s;
    }
    return fmi3OK;
}

/* The model has only Float64 variables: every other type's getter and setter accepts an
 * empty call and refuses any reference. */
#define NO_VARIABLES_OF(Name, Type)                                                         \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference vr[],          \
                             size_t nvr, Type values[], size_t nValues) {                   \
        return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no " #Name " variables");  \
    }                                                                                       \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference vr[],          \
                             size_t nvr, const Type values[], size_t nValues) {             \
        return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no " #Name " variables");  \
    }
NO_VARIABLES_OF(Float32, fmi3Float32)
NO_VARIABLES_OF(Int8, fmi3Int8)
NO_VARIABLES_OF(UInt8, fmi3UInt8)
NO_VARIABLES_OF(Int16, fmi3Int16)
NO_VARIABLES_OF(UInt16, fmi3UInt16)
NO_VARIABLES_OF(Int32, fmi3Int32)
NO_VARIABLES_OF(UInt32, fmi3UInt32)
NO_VARIABLES_OF(Int64, fmi3Int64)
NO_VARIABLES_OF(UInt64, fmi3UInt64)
NO_VARIABLES_OF(Boolean, fmi3Boolean)
NO_VARIABLES_OF(String, fmi3String)
#undef NO_VARIABLES_OF

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no Binary variables");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no Binary variables");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no clocks");
}

#include "fmi3_cs_common.h"

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    Instance *in = (Instance *)instance;
    fmi3Status s;
    if (in == NULL || eventHandlingNeeded == NULL || terminateSimulation == NULL ||
        earlyReturn == NULL || lastSuccessfulTime == NULL)
        return fmi3Error;
    *eventHandlingNeeded = false;
    *terminateSimulation = false;
    *earlyReturn = false;
    *lastSuccessfulTime = in->d.time;
    if (in->mode != MODE_STEP) return refuse(in, "fmi3DoStep outside step mode");
    if (!(communicationStepSize > 0.0)) return refuse(in, "fmi3DoStep with a step size <= 0");
    s = model_do_step(in, currentCommunicationPoint, communicationStepSize);
    if (s == fmi3OK) in->d.time = currentCommunicationPoint + communicationStepSize;
    *lastSuccessfulTime = in->d.time;
#ifdef MSD3_TERMINATE_AT
    if (s == fmi3OK && in->d.time >= MSD3_TERMINATE_AT) *terminateSimulation = true;
#endif
    return s;
}

/* ---- Scheduled execution: not this FMU's interface ---- */

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    return refuse((Instance *)instance, "co-simulation only");
}
