/*
 * Mass-spring-damper, a test FMU for dsmcosim (FMI 2.0 co-simulation):
 *
 *     m x'' = -k x - c x' + F
 *
 * F is an input held constant over each communication step (zero-order hold). Each
 * fmi2DoStep(t, h) integrates with classic RK4 over n = ceil(h / 1e-4) equal substeps,
 * so the result is near the exact solution. Outputs x, v and the acceleration a with
 * the current input. A state is a copy of ModelData; it serializes as its doubles.
 */
#define MODEL_GUID "{6c1c8e0a-5d0e-4b8e-9a57-3a1f0b6d2f01}"
#define MODEL_CAN_GET_SET_STATE 1

#include "msd_model.h"
#include "fmi2_cs_functions.h"

enum { VR_M, VR_K, VR_C, VR_X0, VR_V0, VR_F, VR_X, VR_V, VR_A };

static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value) {
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
    default: return refuse(in, "unknown Real value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value) {
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
    (void)t;
    if (msd_integrate(&in->d, h) != 0) return refuse(in, "the state is no longer finite");
    return fmi2OK;
}
