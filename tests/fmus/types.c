/*
 * A test FMU (FMI 2.0 co-simulation) with an output of every FMI 2.0 type, after the
 * Modelica Reference FMUs' Feedthrough (written anew): a parameter, an input and an
 * output of each type, each output computed from the step count n (the number of
 * completed fmi2DoStep calls), its parameter and, where there is one, its input as last
 * set:
 *
 *     r_out = r_p * n + r_in                 Real
 *     i_out = i_p + i_in + n                 Integer (int arithmetic)
 *     b_out = b_p xor b_in xor (n is odd)    Boolean
 *     s_out = s_p " #" n                     String ("%s #%d")
 *     e_out = 1 + (e_p - 1 + n) mod 3        Enumeration (of 1, 2, 3)
 *
 * tests/fmu/types.rs computes the same values and compares each trace column with them.
 * A state is a copy of ModelData (the strings are held in it), serialized as its bytes.
 */
#include <stdio.h>
#include <string.h>

#define MODEL_GUID "{5d0c9e3a-1f47-4b8e-9a62-7e3d2c1b0a95}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_BOOLEAN_AND_STRING

#define TEXT_BYTES 64

typedef struct {
    double r_p;          /* parameter */
    int i_p, b_p, e_p;   /* parameters: Integer, Boolean, Enumeration */
    char s_p[TEXT_BYTES]; /* parameter: String */
    double r_in;         /* inputs */
    int i_in, b_in;
    int n;               /* steps completed */
    char s_out[TEXT_BYTES + 16]; /* the last s_out given */
    double time;         /* [s] */
} ModelData;

#include "fmi2_cs_functions.h"

enum {
    VR_R_P, VR_I_P, VR_B_P, VR_S_P, VR_E_P,
    VR_R_IN, VR_I_IN, VR_B_IN,
    VR_R_OUT, VR_I_OUT, VR_B_OUT, VR_S_OUT, VR_E_OUT
};

static void model_defaults(ModelData *d) {
    memset(d, 0, sizeof *d);
    d->r_p = 0.5;
    d->i_p = 1000;
    d->b_p = 0;
    d->e_p = 2;
    strcpy(d->s_p, "a, \"b\"");
}

/* Parameters are fixed: set only before initialization ends. */
static int fixed_settable(const Instance *in) {
    return in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION;
}

static fmi2Status model_get_real(Instance *in, fmi2ValueReference vr, fmi2Real *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_R_P: *value = d->r_p; break;
    case VR_R_IN: *value = d->r_in; break;
    case VR_R_OUT: *value = d->r_p * d->n + d->r_in; break;
    default: return refuse(in, "unknown Real value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_real(Instance *in, fmi2ValueReference vr, fmi2Real value) {
    if (vr == VR_R_IN) {
        in->d.r_in = value;
        return fmi2OK;
    }
    if (vr != VR_R_P) return refuse(in, "only r_p and r_in can be set as Real");
    if (!fixed_settable(in)) return refuse(in, "a fixed parameter is set only before initialization ends");
    in->d.r_p = value;
    return fmi2OK;
}

static fmi2Status model_get_integer(Instance *in, fmi2ValueReference vr, fmi2Integer *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_I_P: *value = d->i_p; break;
    case VR_E_P: *value = d->e_p; break;
    case VR_I_IN: *value = d->i_in; break;
    case VR_I_OUT: *value = d->i_p + d->i_in + d->n; break;
    case VR_E_OUT: *value = 1 + (d->e_p - 1 + d->n) % 3; break;
    default: return refuse(in, "unknown Integer or Enumeration value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_integer(Instance *in, fmi2ValueReference vr, fmi2Integer value) {
    if (vr == VR_I_IN) {
        in->d.i_in = value;
        return fmi2OK;
    }
    if (vr != VR_I_P && vr != VR_E_P) return refuse(in, "only i_p, e_p and i_in can be set as Integer");
    if (!fixed_settable(in)) return refuse(in, "a fixed parameter is set only before initialization ends");
    if (vr == VR_E_P && (value < 1 || value > 3)) return refuse(in, "e_p is 1, 2 or 3");
    if (vr == VR_I_P) in->d.i_p = value;
    else in->d.e_p = value;
    return fmi2OK;
}

static fmi2Status model_get_boolean(Instance *in, fmi2ValueReference vr, fmi2Boolean *value) {
    const ModelData *d = &in->d;
    switch (vr) {
    case VR_B_P: *value = d->b_p; break;
    case VR_B_IN: *value = d->b_in; break;
    case VR_B_OUT: *value = (d->b_p != 0) ^ (d->b_in != 0) ^ (d->n % 2 != 0); break;
    default: return refuse(in, "unknown Boolean value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_boolean(Instance *in, fmi2ValueReference vr, fmi2Boolean value) {
    if (vr == VR_B_IN) {
        in->d.b_in = value != 0;
        return fmi2OK;
    }
    if (vr != VR_B_P) return refuse(in, "only b_p and b_in can be set as Boolean");
    if (!fixed_settable(in)) return refuse(in, "a fixed parameter is set only before initialization ends");
    in->d.b_p = value != 0;
    return fmi2OK;
}

static fmi2Status model_get_string(Instance *in, fmi2ValueReference vr, fmi2String *value) {
    ModelData *d = &in->d;
    switch (vr) {
    case VR_S_P: *value = d->s_p; break;
    case VR_S_OUT:
        snprintf(d->s_out, sizeof d->s_out, "%s #%d", d->s_p, d->n);
        *value = d->s_out;
        break;
    default: return refuse(in, "unknown String value reference");
    }
    return fmi2OK;
}

static fmi2Status model_set_string(Instance *in, fmi2ValueReference vr, fmi2String value) {
    if (vr != VR_S_P) return refuse(in, "only s_p can be set as String");
    if (!fixed_settable(in)) return refuse(in, "a fixed parameter is set only before initialization ends");
    if (value == NULL || strlen(value) >= TEXT_BYTES) return refuse(in, "s_p: at most 63 bytes");
    strcpy(in->d.s_p, value);
    return fmi2OK;
}

static fmi2Status model_do_step(Instance *in, fmi2Real t, fmi2Real h) {
    (void)t;
    (void)h;
    in->d.n += 1;
    return fmi2OK;
}
