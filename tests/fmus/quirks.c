/*
 * A test FMU (FMI 2.0 co-simulation) that does, at set times, the things a real FMU may
 * do that are not plain errors: a free unit mass x'' = F (input F [N], outputs x [m],
 * v [m/s], integrated exactly for F held over the step), which
 *   - asks to stop (as the Modelica Reference FMUs' Stair does): the step that reaches
 *     stop_at [s] is completed, then fmi2DoStep returns fmi2Discard with
 *     fmi2GetBooleanStatus(fmi2Terminated) true;
 *   - logs a warning through the importer's logger, whether logging is on or not, at
 *     every step that ends at or after warn_from [s], its text naming the step's end;
 *   - logs an error and returns fmi2Error from a step that would end past fail_at [s]
 *     (the text a tool's FMU gives when its data file is missing);
 *   - gives x = NaN from the step that ends past nan_at [s] on;
 *   - declares canGetAndSetFMUstate, yet fmi2GetFMUstate fails when fail_get_state = 1.
 * Every time parameter defaults to 1e9 s: never, in any test.
 */
#include <math.h>
#include <stdio.h>

#define MODEL_GUID "{8e41d2a7-5b0c-4f3e-a6d9-2c7b1e0f9a34}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_REFUSES_STATE(in) ((in)->d.fail_get_state != 0.0)

typedef struct {
    double stop_at, warn_from, fail_at, nan_at; /* parameters [s] */
    double fail_get_state;                      /* parameter, 0 or 1 (an Integer) */
    double F;                                   /* input [N] */
    double x, v;                                /* state [m], [m/s] */
    double time;                                /* [s] */
} ModelData;

#include "fmi2_cs_functions.h"

enum { VR_STOP_AT, VR_WARN_FROM, VR_FAIL_AT, VR_NAN_AT, VR_FAIL_GET_STATE, VR_F, VR_X, VR_V };

static void model_defaults(ModelData *d) {
    d->stop_at = 1e9;
    d->warn_from = 1e9;
    d->fail_at = 1e9;
    d->nan_at = 1e9;
    d->fail_get_state = 0.0;
    d->F = 0.0;
    d->x = 0.0;
    d->v = 0.0;
    d->time = 0.0;
}

static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_STOP_AT: *value = d->stop_at; break;
    case VR_WARN_FROM: *value = d->warn_from; break;
    case VR_FAIL_AT: *value = d->fail_at; break;
    case VR_NAN_AT: *value = d->nan_at; break;
    case VR_F: *value = d->F; break;
    case VR_X: *value = d->x; break;
    case VR_V: *value = d->v; break;
    default: return refuse(in, "unknown Real value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value) {
    ModelData *d = &in->d;
    if (vr != VR_F && in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    switch (vr) {
    case VR_STOP_AT: d->stop_at = value; break;
    case VR_WARN_FROM: d->warn_from = value; break;
    case VR_FAIL_AT: d->fail_at = value; break;
    case VR_NAN_AT: d->nan_at = value; break;
    case VR_F: d->F = value; break;
    default: return refuse(in, "only the parameters and the input F can be set as Real");
    }
    return fmi2OK;
}

static fmi2Status model_get_integer(Instance *in, fmi2ValueReference vr, fmi2Integer *value) {
    if (vr != VR_FAIL_GET_STATE) return refuse(in, "unknown Integer value reference");
    *value = (fmi2Integer)in->d.fail_get_state;
    return fmi2OK;
}

static fmi2Status model_set_integer(Instance *in, fmi2ValueReference vr, fmi2Integer value) {
    if (vr != VR_FAIL_GET_STATE) return refuse(in, "unknown Integer value reference");
    if (in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    in->d.fail_get_state = value != 0 ? 1.0 : 0.0;
    return fmi2OK;
}

static fmi2Status model_do_step(Instance *in, fmi2Real t, fmi2Real h) {
    ModelData *d = &in->d;
    double end = t + h;
    if (end > d->fail_at)
        return refuse(in, "Failed to open resource file table.csv: no data past fail_at");
    d->x += d->v * h + 0.5 * d->F * h * h;
    d->v += d->F * h;
    if (end > d->nan_at) d->x = NAN;
    if (end >= d->warn_from && in->cb.logger != NULL) {
        char text[96];
        snprintf(text, sizeof text, "step to t = %.9g s past warn_from", end);
        in->cb.logger(in->cb.componentEnvironment, in->name, fmi2Warning, "logStatusWarning",
                      text);
    }
    if (end >= d->stop_at) {
        in->terminated = 1;
        return fmi2Discard;
    }
    return fmi2OK;
}
