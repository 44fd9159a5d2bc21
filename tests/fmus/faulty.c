/*
 * A deliberately failing FMU for dsmcosim's error tests (FMI 2.0 co-simulation): a free
 * unit mass, x'' = F (input F [N], outputs x [m], v [m/s], integrated exactly for F held
 * over the step), whose fmi2DoStep
 *   - returns fmi2Error for a step that would end past the parameter fail_at [s], and
 *   - when the parameter crash = 1, writes through a null pointer (SIGSEGV), so the
 *     importer's test can check that a crash ends the process by a signal.
 */
#include <stddef.h>

#define MODEL_GUID "{c2b7e4f1-93d6-4e0a-8f15-7d4a6e2c1b03}"
#define MODEL_CAN_GET_SET_STATE 0

typedef struct {
    double fail_at; /* parameter [s] */
    double crash;   /* parameter, 0 or 1 (an Integer at the interface) */
    double F;       /* input [N] */
    double x, v;    /* state [m], [m/s] */
    double time;    /* [s] */
} ModelData;

#include "fmi2_cs_functions.h"

enum { VR_FAIL_AT, VR_CRASH, VR_F, VR_X, VR_V };

static void model_defaults(ModelData *d) {
    d->fail_at = 0.5;
    d->crash = 0.0;
    d->F = 0.0;
    d->x = 0.0;
    d->v = 0.0;
    d->time = 0.0;
}

static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_FAIL_AT: *value = d->fail_at; break;
    case VR_F: *value = d->F; break;
    case VR_X: *value = d->x; break;
    case VR_V: *value = d->v; break;
    default: return refuse(in, "unknown Real value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value) {
    ModelData *d = &in->d;
    if (vr == VR_FAIL_AT && in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    switch (vr) {
    case VR_FAIL_AT: d->fail_at = value; break;
    case VR_F: d->F = value; break;
    default: return refuse(in, "only fail_at and the input F can be set as Real");
    }
    return fmi2OK;
}

static fmi2Status model_get_integer(Instance *in, fmi2ValueReference vr, fmi2Integer *value) {
    if (vr != VR_CRASH) return refuse(in, "unknown Integer value reference");
    *value = (fmi2Integer)in->d.crash;
    return fmi2OK;
}

static fmi2Status model_set_integer(Instance *in, fmi2ValueReference vr, fmi2Integer value) {
    if (vr != VR_CRASH) return refuse(in, "unknown Integer value reference");
    if (in->mode != MODE_INSTANTIATED && in->mode != MODE_INITIALIZATION)
        return refuse(in, "a fixed parameter is set only before initialization ends");
    in->d.crash = value != 0 ? 1.0 : 0.0;
    return fmi2OK;
}

static fmi2Status model_do_step(Instance *in, fmi2Real t, fmi2Real h) {
    ModelData *d = &in->d;
    if (d->crash != 0.0) {
        /* Volatile, so the compiler cannot see the null and turn the store into a trap
         * instruction (SIGILL) instead of a memory fault (SIGSEGV). */
        int *volatile target = NULL;
        *target = 1;
    }
    if (t + h > d->fail_at) return refuse(in, "the step would end past fail_at");
    d->x += d->v * h + 0.5 * d->F * h * h;
    d->v += d->F * h;
    return fmi2OK;
}
