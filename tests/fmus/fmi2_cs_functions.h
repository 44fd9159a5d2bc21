/*
 * The FMI 2.0 co-simulation functions every test FMU shares: instance life cycle, modes,
 * value access, saved states and the functions these models do not support.
 *
 * A model source defines, before including this file:
 *   MODEL_GUID               the guid of its modelDescription.xml
 *   MODEL_CAN_GET_SET_STATE  1 if the description declares canGetAndSetFMUstate and
 *                            canSerializeFMUstate (a state is a copy of ModelData,
 *                            serialized as its bytes), else 0
 *   ModelData                a struct of its variables with a `double time` member
 * and, after including it, the model_* functions declared below. Optionally:
 *   MODEL_REFUSES_STATE(in)  an expression true when fmi2GetFMUstate must fail (a model
 *                            whose state saving breaks; default: never)
 *   MODEL_HAS_BOOLEAN_AND_STRING  defined when the model has Boolean and String
 *                            variables: it then provides model_get_boolean,
 *                            model_set_boolean, model_get_string and model_set_string
 *                            (a String it gives stays valid until its next call)
 * A model asks to stop by setting `in->terminated` and returning fmi2Discard from
 * model_do_step after completing the step: fmi2GetBooleanStatus(fmi2Terminated) then
 * answers true and the time advances to the step's end.
 */
#ifndef DSMCOSIM_FMI2_CS_FUNCTIONS_H
#define DSMCOSIM_FMI2_CS_FUNCTIONS_H

#include <stdio.h>
#include <string.h>

#include "fmi2_abi.h"

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED } Mode;

typedef struct {
    ModelData d;
    fmi2CallbackFunctions cb;
    char *name;
    Mode mode;
    int logging;
    int terminated; /* the model asked to end the simulation */
} Instance;

#ifndef MODEL_REFUSES_STATE
#define MODEL_REFUSES_STATE(in) 0
#endif

/* What each model provides. */
static void model_defaults(ModelData *d);
static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value);
static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value);
static fmi2Status model_get_integer(Instance *in, fmi2ValueReference vr, fmi2Integer *value);
static fmi2Status model_set_integer(Instance *in, fmi2ValueReference vr, fmi2Integer value);
static fmi2Status model_do_step(Instance *in, fmi2Real t, fmi2Real h);
#ifdef MODEL_HAS_BOOLEAN_AND_STRING
static fmi2Status model_get_boolean(Instance *in, fmi2ValueReference vr, fmi2Boolean *value);
static fmi2Status model_set_boolean(Instance *in, fmi2ValueReference vr, fmi2Boolean value);
static fmi2Status model_get_string(Instance *in, fmi2ValueReference vr, fmi2String *value);
static fmi2Status model_set_string(Instance *in, fmi2ValueReference vr, fmi2String value);
#endif

/* Logs `message` through the importer: errors always, the rest when logging is on. The
 * text is formatted here and any '%' dropped, so importers that printf the message and
 * importers that print it as-is show the same thing. */
static void log_text(Instance *in, fmi2Status status, const char *category, const char *message) {
    char buf[256];
    size_t j = 0;
    if (in == NULL || in->cb.logger == NULL || (!in->logging && status < fmi2Error)) return;
    for (size_t i = 0; message[i] != '\0' && j + 1 < sizeof buf; i++) {
        if (message[i] != '%') buf[j++] = message[i];
    }
    buf[j] = '\0';
    in->cb.logger(in->cb.componentEnvironment, in->name, status, category, buf);
}

static fmi2Status refuse(Instance *in, const char *what) {
    log_text(in, fmi2Error, "logStatusError", what);
    return fmi2Error;
}

const char *fmi2GetTypesPlatform(void) { return "default"; }
const char *fmi2GetVersion(void) { return "2.0"; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance *in = (Instance *)c;
    (void)nCategories;
    (void)categories;
    if (in == NULL) return fmi2Error;
    in->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Instance *in;
    size_t len;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL)
        return NULL;
    if (instanceName == NULL || fmuType != fmi2CoSimulation || fmuGUID == NULL ||
        strcmp(fmuGUID, MODEL_GUID) != 0)
        return NULL;
    in = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (in == NULL) return NULL;
    len = strlen(instanceName);
    in->name = (char *)functions->allocateMemory(len + 1, 1);
    if (in->name == NULL) {
        functions->freeMemory(in);
        return NULL;
    }
    memcpy(in->name, instanceName, len + 1);
    in->cb = *functions;
    in->logging = loggingOn;
    in->mode = MODE_INSTANTIATED;
    model_defaults(&in->d);
    log_text(in, fmi2OK, "logEvents", "instantiated");
    return in;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *in = (Instance *)c;
    fmi2CallbackFreeMemory release;
    if (in == NULL) return;
    release = in->cb.freeMemory;
    release(in->name);
    release(in);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    Instance *in = (Instance *)c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (in == NULL) return fmi2Error;
    if (in->mode != MODE_INSTANTIATED) return refuse(in, "fmi2SetupExperiment after initialization");
    in->d.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    if (in->mode != MODE_INSTANTIATED) return refuse(in, "fmi2EnterInitializationMode twice");
    in->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    if (in->mode != MODE_INITIALIZATION)
        return refuse(in, "fmi2ExitInitializationMode outside initialization mode");
    in->mode = MODE_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    in->mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    model_defaults(&in->d);
    in->mode = MODE_INSTANTIATED;
    in->terminated = 0;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s = model_get_real(in, vr[i], &value[i]);
        if (s != fmi2OK) return s;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s = model_set_real(in, vr[i], value[i]);
        if (s != fmi2OK) return s;
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s = model_get_integer(in, vr[i], &value[i]);
        if (s != fmi2OK) return s;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    Instance *in = (Instance *)c;
    if (in == NULL) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s = model_set_integer(in, vr[i], value[i]);
        if (s != fmi2OK) return s;
    }
    return fmi2OK;
}

#ifdef MODEL_HAS_BOOLEAN_AND_STRING
/* Each call's values through the model's hooks, reference by reference. */
#define BY_REFERENCE(hook, value_i)                                                         \
    Instance *in = (Instance *)c;                                                           \
    if (in == NULL) return fmi2Error;                                                       \
    for (size_t i = 0; i < nvr; i++) {                                                      \
        fmi2Status s = hook(in, vr[i], value_i);                                            \
        if (s != fmi2OK) return s;                                                          \
    }                                                                                       \
    return fmi2OK;

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    BY_REFERENCE(model_get_boolean, &value[i])
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    BY_REFERENCE(model_set_boolean, value[i])
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    BY_REFERENCE(model_get_string, &value[i])
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    BY_REFERENCE(model_set_string, value[i])
}
#undef BY_REFERENCE
#else
/* The model has no Boolean or String variables. */
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : refuse((Instance *)c, "no Boolean variables");
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : refuse((Instance *)c, "no Boolean variables");
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : refuse((Instance *)c, "no String variables");
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)vr;
    (void)value;
    return nvr == 0 ? fmi2OK : refuse((Instance *)c, "no String variables");
}

#endif

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Instance *in = (Instance *)c;
    ModelData *copy;
    if (in == NULL || state == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU cannot save its state");
    if (MODEL_REFUSES_STATE(in)) return refuse(in, "the model refuses to save its state");
    copy = (ModelData *)*state;
    if (copy == NULL) copy = (ModelData *)in->cb.allocateMemory(1, sizeof(ModelData));
    if (copy == NULL) return refuse(in, "out of memory");
    *copy = in->d;
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Instance *in = (Instance *)c;
    if (in == NULL || state == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU cannot restore a state");
    in->d = *(const ModelData *)state;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Instance *in = (Instance *)c;
    if (in == NULL || state == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU has no states to free");
    if (*state != NULL) in->cb.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    Instance *in = (Instance *)c;
    (void)state;
    if (in == NULL || size == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU cannot serialize a state");
    *size = sizeof(ModelData);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Instance *in = (Instance *)c;
    if (in == NULL || state == NULL || bytes == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU cannot serialize a state");
    if (size != sizeof(ModelData)) return refuse(in, "wrong buffer size for a state");
    memcpy(bytes, state, sizeof(ModelData));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Instance *in = (Instance *)c;
    ModelData *copy;
    if (in == NULL || bytes == NULL || state == NULL) return fmi2Error;
    if (!MODEL_CAN_GET_SET_STATE) return refuse(in, "this FMU cannot deserialize a state");
    if (size != sizeof(ModelData)) return refuse(in, "serialized state has the wrong size");
    copy = (ModelData *)*state;
    if (copy == NULL) copy = (ModelData *)in->cb.allocateMemory(1, sizeof(ModelData));
    if (copy == NULL) return refuse(in, "out of memory");
    memcpy(copy, bytes, sizeof(ModelData));
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[],
                                        size_t nUnknown, const fmi2ValueReference knowns[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)unknowns;
    (void)nUnknown;
    (void)knowns;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return refuse((Instance *)c, "no directional derivatives");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return refuse((Instance *)c, "inputs are held constant over a step: no input derivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return refuse((Instance *)c, "no output derivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *in = (Instance *)c;
    fmi2Status s;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (in == NULL) return fmi2Error;
    if (in->mode != MODE_STEP) return refuse(in, "fmi2DoStep outside step mode");
    if (!(communicationStepSize > 0.0)) return refuse(in, "fmi2DoStep with a step size <= 0");
    if (in->terminated) return refuse(in, "fmi2DoStep after the model asked to terminate");
    s = model_do_step(in, currentCommunicationPoint, communicationStepSize);
    if (s == fmi2OK || (s == fmi2Discard && in->terminated))
        in->d.time = currentCommunicationPoint + communicationStepSize;
    return s;
}

/* Steps are synchronous: nothing to cancel or poll. */
fmi2Status fmi2CancelStep(fmi2Component c) { return refuse((Instance *)c, "no asynchronous step"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    if (c == NULL || value == NULL || s != fmi2DoStepStatus) return fmi2Discard;
    *value = fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Instance *in = (Instance *)c;
    if (in == NULL || value == NULL || s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = in->d.time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s;
    (void)value;
    return refuse((Instance *)c, "no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Instance *in = (Instance *)c;
    if (in == NULL || value == NULL || s != fmi2Terminated) return fmi2Discard;
    *value = in->terminated ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s;
    (void)value;
    return refuse((Instance *)c, "no string status");
}

#endif
