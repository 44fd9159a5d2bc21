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
#include <math.h>

#define MODEL_GUID "{6c1c8e0a-5d0e-4b8e-9a57-3a1f0b6d2f01}"
#define MODEL_CAN_GET_SET_STATE 1

typedef struct {
    double m, k, c, x0, v0; /* parameters [kg], [N/m], [N s/m], [m], [m/s] */
    double F;               /* input [N] */
    double x, v;            /* state [m], [m/s] */
    double time;            /* [s] */
} ModelData;

#include "fmi2_cs_functions.h"

enum { VR_M, VR_K, VR_C, VR_X0, VR_V0, VR_F, VR_X, VR_V, VR_A };

/* Largest internal RK4 step [s]. */
#define MAX_SUBSTEP 1e-4

static void model_defaults(ModelData *d) {
    d->m = 1.0;
    d->k = 4.0;
    d->c = 0.4;
    d->x0 = 1.0;
    d->v0 = 0.0;
    d->F = 0.0;
    d->x = d->x0;
    d->v = d->v0;
    d->time = 0.0;
}

static double acceleration(const ModelData *d, double x, double v) {
    return (d->F - d->k * x - d->c * v) / d->m;
}

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
    ModelData *d = &in->d;
    /* The small margin keeps h = 1 ms at 10 substeps despite 1e-3 / 1e-4 rounding up. */
    long n = (long)ceil(h / MAX_SUBSTEP - 1e-9);
    double dt, x = d->x, v = d->v;
    (void)t;
    if (n < 1) n = 1;
    dt = h / (double)n;
    for (long i = 0; i < n; i++) {
        double k1x = v, k1v = acceleration(d, x, v);
        double k2x = v + 0.5 * dt * k1v, k2v = acceleration(d, x + 0.5 * dt * k1x, k2x);
        double k3x = v + 0.5 * dt * k2v, k3v = acceleration(d, x + 0.5 * dt * k2x, k3x);
        double k4x = v + dt * k3v, k4v = acceleration(d, x + dt * k3x, k4x);
        x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    if (!isfinite(x) || !isfinite(v) || !isfinite(acceleration(d, x, v)))
        return refuse(in, "the state is no longer finite");
    d->x = x;
    d->v = v;
    return fmi2OK;
}
