/*
 * PD controller, a test FMU for dsmcosim (FMI 2.0 co-simulation):
 *
 *     u = -kp (x - r) - kd v
 *
 * u is a direct-feedthrough algebraic output computed from the current inputs x, v
 * whenever it is read; fmi2DoStep only advances time. Its state (parameters, held
 * inputs, time) can be saved and serialized, so a co-simulation of a loop with it can
 * fork and checkpoint.
 */
#define MODEL_GUID "{0f6d3b52-8a3c-4c39-b1f2-2c5e9d7a4b02}"
#define MODEL_CAN_GET_SET_STATE 1

typedef struct {
    double kp, kd, r; /* parameters [N/m], [N s/m], [m] */
    double x, v;      /* inputs [m], [m/s] */
    double time;      /* [s] */
} ModelData;

#include "fmi2_cs_functions.h"

enum { VR_KP, VR_KD, VR_R, VR_X, VR_V, VR_U };

static void model_defaults(ModelData *d) {
    d->kp = 10.0;
    d->kd = 2.0;
    d->r = 0.0;
    d->x = 0.0;
    d->v = 0.0;
    d->time = 0.0;
}

static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_KP: *value = d->kp; break;
    case VR_KD: *value = d->kd; break;
    case VR_R: *value = d->r; break;
    case VR_X: *value = d->x; break;
    case VR_V: *value = d->v; break;
    case VR_U: *value = -d->kp * (d->x - d->r) - d->kd * d->v; break;
    default: return refuse(in, "unknown Real value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value) {
    ModelData *d = &in->d;
    if (vr <= VR_R && in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    switch (vr) {
    case VR_KP: d->kp = value; break;
    case VR_KD: d->kd = value; break;
    case VR_R: d->r = value; break;
    case VR_X: d->x = value; break;
    case VR_V: d->v = value; break;
    default: return refuse(in, "only parameters and the inputs x, v can be set");
    }
    return fmi2OK;
}

static fmi2Status model_get_integer(Instance *in, fmi2ValueReference vr, fmi2Integer *value) {
    (void)vr;
    (void)value;
    return refuse(in, "no Integer variables");
}

static fmi2Status model_set_integer(Instance *in, fmi2ValueReference vr, fmi2Integer value) {
    (void)vr;
    (void)value;
    return refuse(in, "no Integer variables");
}

static fmi2Status model_do_step(Instance *in, fmi2Real t, fmi2Real h) {
    (void)in;
    (void)t;
    (void)h;
    return fmi2OK;
}
