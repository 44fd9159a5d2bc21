/*
 * A test FMU (FMI 3.0 co-simulation) with an output of every FMI 3.0 type but Clock and
 * two array outputs, after the Modelica Reference FMUs' Feedthrough and StateSpace
 * (written anew). Each output is computed from the step count n (the number of completed
 * fmi3DoStep calls), a parameter of its type and, for four of them, an input as last
 * set:
 *
 *     f64_out  = f64_p * n + f64_in                  Float64
 *     f32_out  = f32_p * (float)n                    Float32 (float arithmetic)
 *     i8_out   = i8_p - n                            Int8
 *     u8_out   = u8_p + n, modulo 2^8                UInt8
 *     i16_out  = i16_p - 7 n                         Int16
 *     u16_out  = u16_p + 1000 n, modulo 2^16         UInt16
 *     i32_out  = i32_p + i32_in + n                  Int32
 *     u32_out  = u32_p + n, modulo 2^32              UInt32
 *     i64_out  = i64_p + i64_in + n                  Int64
 *     u64_out  = u64_p - n, modulo 2^64              UInt64
 *     bool_out = bool_p xor bool_in xor (n is odd)   Boolean
 *     str_out  = str_p " #" n                        String ("%s #%lld")
 *     bin_out  = the bytes of bin_p, then the byte n mod 2^8    Binary
 *     enum_out = 1 + (enum_p - 1 + n) mod 3          Enumeration (of 1, 2, 3)
 *     y[i]     = f64_p * i + n, i = 1 … n_y          Float64 array, its size the
 *                                                    structural parameter n_y (start 3)
 *     z[i]     = i * n, i = 1, 2                     Int32 array of fixed size 2
 *
 * tests/fmu/types.rs computes the same values and compares each trace column with them.
 * Built with TYPES3_STRING_BYTES defined, str_out is that many bytes of 'x' instead.
 * Every function of the standard is exported; those this model does not support answer
 * fmi3Error. A state is a copy of ModelData (strings and bytes held in it).
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3_abi.h"

#define MODEL_TOKEN "{c8a4e1f6-2b93-4d70-8e15-9f6a3b2c7d48}"

#define TEXT_BYTES 64
#define MAX_Y 16 /* the largest n_y this model holds */

typedef struct {
    /* parameters */
    double f64_p;
    float f32_p;
    int8_t i8_p;
    uint8_t u8_p;
    int16_t i16_p;
    uint16_t u16_p;
    int32_t i32_p;
    uint32_t u32_p;
    int64_t i64_p;
    uint64_t u64_p;
    bool bool_p;
    char str_p[TEXT_BYTES];
    uint8_t bin_p[TEXT_BYTES];
    size_t bin_p_size;
    int64_t enum_p;
    uint64_t n_y; /* structural parameter: the size of y */
    /* inputs */
    double f64_in;
    int32_t i32_in;
    int64_t i64_in;
    bool bool_in;
    /* state */
    int64_t n;                          /* steps completed */
    char str_out[TEXT_BYTES + 24];      /* the last str_out given */
    uint8_t bin_out[TEXT_BYTES + 1];    /* the last bin_out given */
    double time;                        /* [s] */
} ModelData;

static void model_defaults(ModelData *d) {
    memset(d, 0, sizeof *d);
    d->f64_p = 0.5;
    d->f32_p = 0.1f;
    d->i8_p = -100;
    d->u8_p = 250;
    d->i16_p = -30000;
    d->u16_p = 60000;
    d->i32_p = 1000;
    d->u32_p = 4294967290u;
    d->i64_p = INT64_C(9007199254740993); /* 2^53 + 1: no double holds it */
    d->u64_p = UINT64_C(18446744073709551615);
    d->bool_p = false;
    strcpy(d->str_p, "a, \"b\"");
    d->bin_p[0] = 0x00;
    d->bin_p[1] = 0xff;
    d->bin_p_size = 2;
    d->enum_p = 2;
    d->n_y = 3;
}

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED } Mode;

typedef struct {
    ModelData d;
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
    Mode mode;
    bool logging;
} Instance;

enum {
    VR_TIME,
    VR_F64_P, VR_F32_P, VR_I8_P, VR_U8_P, VR_I16_P, VR_U16_P, VR_I32_P, VR_U32_P, VR_I64_P,
    VR_U64_P, VR_BOOL_P, VR_STR_P, VR_BIN_P, VR_ENUM_P, VR_N_Y,
    VR_F64_IN, VR_I32_IN, VR_I64_IN, VR_BOOL_IN,
    VR_F64_OUT, VR_F32_OUT, VR_I8_OUT, VR_U8_OUT, VR_I16_OUT, VR_U16_OUT, VR_I32_OUT,
    VR_U32_OUT, VR_I64_OUT, VR_U64_OUT, VR_BOOL_OUT, VR_STR_OUT, VR_BIN_OUT, VR_ENUM_OUT,
    VR_Y, VR_Z
};

/* Logs through the importer: errors always, the rest when logging is on. */
static void log_text(Instance *in, fmi3Status status, const char *category, const char *message) {
    if (in == NULL || in->log == NULL || (!in->logging && status < fmi3Error)) return;
    in->log(in->env, status, category, message);
}

static fmi3Status refuse(Instance *in, const char *what) {
    log_text(in, fmi3Error, "logStatusError", what);
    return fmi3Error;
}

static fmi3Status model_do_step(Instance *in, fmi3Float64 t, fmi3Float64 h) {
    (void)t;
    (void)h;
    in->d.n += 1;
    return fmi3OK;
}

/* ---- Values ----
 *
 * Each getter walks its references, each giving one value (an array its elements), and
 * checks that they fill exactly the nValues the importer passed. Parameters are fixed:
 * set only before initialization ends; inputs at any time; n_y only in configuration
 * mode, which this FMU does not offer. */

static int settable(const Instance *in, fmi3ValueReference vr) {
    if (vr >= VR_F64_IN && vr <= VR_BOOL_IN) return 1;
    return in->mode == MODE_INSTANTIATED || in->mode == MODE_INITIALIZATION;
}

#define CHECK_INSTANCE                                                                      \
    Instance *in = (Instance *)instance;                                                    \
    size_t k = 0;                                                                           \
    if (in == NULL) return fmi3Error;

#define CHECK_COUNT(Name)                                                                   \
    if (k != nValues) return refuse(in, "fmi3" #Name ": nValues does not match the references"); \
    return fmi3OK;

/* A scalar getter: case VR: value = expression. */
#define GET_ONE(vr_, expr)                                                                  \
    case vr_:                                                                               \
        if (k >= nValues) return refuse(in, "too few values for the references");           \
        values[k++] = (expr);                                                               \
        break;

/* A scalar setter for a variable `field` of ModelData. */
#define SET_ONE(vr_, field)                                                                 \
    case vr_:                                                                               \
        if (!settable(in, vr_)) return refuse(in, "a fixed parameter is set only before initialization ends"); \
        d->field = values[k++];                                                             \
        break;

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    CHECK_INSTANCE
    const ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_TIME, d->time)
            GET_ONE(VR_F64_P, d->f64_p)
            GET_ONE(VR_F64_IN, d->f64_in)
            GET_ONE(VR_F64_OUT, d->f64_p * (double)d->n + d->f64_in)
        case VR_Y:
            if (d->n_y > MAX_Y || k + d->n_y > nValues) return refuse(in, "too few values for y");
            for (uint64_t j = 1; j <= d->n_y; j++) values[k++] = d->f64_p * (double)j + (double)d->n;
            break;
        default: return refuse(in, "unknown Float64 value reference");
        }
    }
    CHECK_COUNT(GetFloat64)
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetFloat64: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            SET_ONE(VR_F64_P, f64_p)
            SET_ONE(VR_F64_IN, f64_in)
        default: return refuse(in, "only f64_p and f64_in can be set as Float64");
        }
    }
    return fmi3OK;
}

/* One scalar numeric type: its parameter, its output, and (optionally) its input. */
#define SCALAR_TYPE(Name, Type, VR_P, field_p, VR_OUT, out_expr)                            \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference vr[],          \
                             size_t nvr, Type values[], size_t nValues) {                   \
        CHECK_INSTANCE                                                                      \
        const ModelData *d = &in->d;                                                        \
        for (size_t i = 0; i < nvr; i++) {                                                  \
            switch (vr[i]) {                                                                \
                GET_ONE(VR_P, d->field_p)                                                   \
                GET_ONE(VR_OUT, out_expr)                                                   \
            default: return refuse(in, "unknown " #Name " value reference");                \
            }                                                                               \
        }                                                                                   \
        CHECK_COUNT(Get##Name)                                                              \
    }                                                                                       \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference vr[],          \
                             size_t nvr, const Type values[], size_t nValues) {             \
        CHECK_INSTANCE                                                                      \
        ModelData *d = &in->d;                                                              \
        if (nValues != nvr) return refuse(in, "fmi3Set" #Name ": scalars only");            \
        for (size_t i = 0; i < nvr; i++) {                                                  \
            switch (vr[i]) {                                                                \
                SET_ONE(VR_P, field_p)                                                      \
            default: return refuse(in, "only the " #Name " parameter can be set");          \
            }                                                                               \
        }                                                                                   \
        return fmi3OK;                                                                      \
    }

SCALAR_TYPE(Float32, fmi3Float32, VR_F32_P, f32_p, VR_F32_OUT, d->f32_p * (float)d->n)
SCALAR_TYPE(Int8, fmi3Int8, VR_I8_P, i8_p, VR_I8_OUT, (int8_t)(d->i8_p - d->n))
SCALAR_TYPE(UInt8, fmi3UInt8, VR_U8_P, u8_p, VR_U8_OUT, (uint8_t)(d->u8_p + (uint64_t)d->n))
SCALAR_TYPE(Int16, fmi3Int16, VR_I16_P, i16_p, VR_I16_OUT, (int16_t)(d->i16_p - 7 * d->n))
SCALAR_TYPE(UInt16, fmi3UInt16, VR_U16_P, u16_p, VR_U16_OUT,
            (uint16_t)(d->u16_p + 1000 * (uint64_t)d->n))
SCALAR_TYPE(UInt32, fmi3UInt32, VR_U32_P, u32_p, VR_U32_OUT, (uint32_t)(d->u32_p + (uint64_t)d->n))
#undef SCALAR_TYPE

/* UInt64: u64_p, u64_out and the structural parameter n_y (read only). */
fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         fmi3UInt64 values[], size_t nValues) {
    CHECK_INSTANCE
    const ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_U64_P, d->u64_p)
            GET_ONE(VR_U64_OUT, d->u64_p - (uint64_t)d->n)
            GET_ONE(VR_N_Y, d->n_y)
        default: return refuse(in, "unknown UInt64 value reference");
        }
    }
    CHECK_COUNT(GetUInt64)
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetUInt64: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            SET_ONE(VR_U64_P, u64_p)
        case VR_N_Y: return refuse(in, "n_y is a structural parameter: set only in configuration mode");
        default: return refuse(in, "only u64_p can be set as UInt64");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int32 values[], size_t nValues) {
    CHECK_INSTANCE
    const ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_I32_P, d->i32_p)
            GET_ONE(VR_I32_IN, d->i32_in)
            GET_ONE(VR_I32_OUT, (int32_t)(d->i32_p + d->i32_in + d->n))
        case VR_Z:
            if (k + 2 > nValues) return refuse(in, "too few values for z");
            values[k++] = (int32_t)(1 * d->n);
            values[k++] = (int32_t)(2 * d->n);
            break;
        default: return refuse(in, "unknown Int32 value reference");
        }
    }
    CHECK_COUNT(GetInt32)
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int32 values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetInt32: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            SET_ONE(VR_I32_P, i32_p)
            SET_ONE(VR_I32_IN, i32_in)
        default: return refuse(in, "only i32_p and i32_in can be set as Int32");
        }
    }
    return fmi3OK;
}

/* Int64: i64_p, i64_in, i64_out, and the enumeration's (FMI 3.0 passes it as Int64). */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Int64 values[], size_t nValues) {
    CHECK_INSTANCE
    const ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_I64_P, d->i64_p)
            GET_ONE(VR_I64_IN, d->i64_in)
            GET_ONE(VR_I64_OUT, d->i64_p + d->i64_in + d->n)
            GET_ONE(VR_ENUM_P, d->enum_p)
            GET_ONE(VR_ENUM_OUT, 1 + (d->enum_p - 1 + d->n) % 3)
        default: return refuse(in, "unknown Int64 or Enumeration value reference");
        }
    }
    CHECK_COUNT(GetInt64)
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int64 values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetInt64: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == VR_ENUM_P && (values[i] < 1 || values[i] > 3)) return refuse(in, "enum_p is 1, 2 or 3");
        switch (vr[i]) {
            SET_ONE(VR_I64_P, i64_p)
            SET_ONE(VR_I64_IN, i64_in)
            SET_ONE(VR_ENUM_P, enum_p)
        default: return refuse(in, "only i64_p, i64_in and enum_p can be set as Int64");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues) {
    CHECK_INSTANCE
    const ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_BOOL_P, d->bool_p)
            GET_ONE(VR_BOOL_IN, d->bool_in)
            GET_ONE(VR_BOOL_OUT, d->bool_p ^ d->bool_in ^ (d->n % 2 != 0))
        default: return refuse(in, "unknown Boolean value reference");
        }
    }
    CHECK_COUNT(GetBoolean)
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetBoolean: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            SET_ONE(VR_BOOL_P, bool_p)
            SET_ONE(VR_BOOL_IN, bool_in)
        default: return refuse(in, "only bool_p and bool_in can be set as Boolean");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         fmi3String values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
            GET_ONE(VR_STR_P, d->str_p)
        case VR_STR_OUT:
            if (k >= nValues) return refuse(in, "too few values for the references");
#ifdef TYPES3_STRING_BYTES
            /* A test build: str_out is TYPES3_STRING_BYTES bytes of 'x', for an importer's
             * cap on the values it copies. */
            {
                static char *text = NULL;
                if (text == NULL) text = (char *)malloc(TYPES3_STRING_BYTES + 1);
                if (text == NULL) return refuse(in, "out of memory");
                memset(text, 'x', TYPES3_STRING_BYTES);
                text[TYPES3_STRING_BYTES] = '\0';
                values[k++] = text;
                break;
            }
#endif
            snprintf(d->str_out, sizeof d->str_out, "%s #%" PRId64, d->str_p, d->n);
            values[k++] = d->str_out;
            break;
        default: return refuse(in, "unknown String value reference");
        }
    }
    CHECK_COUNT(GetString)
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetString: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] != VR_STR_P) return refuse(in, "only str_p can be set as String");
        if (!settable(in, vr[i])) return refuse(in, "a fixed parameter is set only before initialization ends");
        if (values[i] == NULL || strlen(values[i]) >= TEXT_BYTES) return refuse(in, "str_p: at most 63 bytes");
        strcpy(d->str_p, values[i]);
        k++;
    }
    return fmi3OK;
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    for (size_t i = 0; i < nvr; i++) {
        if (k >= nValues) return refuse(in, "too few values for the references");
        switch (vr[i]) {
        case VR_BIN_P:
            valueSizes[k] = d->bin_p_size;
            values[k++] = d->bin_p;
            break;
        case VR_BIN_OUT:
            memcpy(d->bin_out, d->bin_p, d->bin_p_size);
            d->bin_out[d->bin_p_size] = (uint8_t)d->n;
            valueSizes[k] = d->bin_p_size + 1;
            values[k++] = d->bin_out;
            break;
        default: return refuse(in, "unknown Binary value reference");
        }
    }
    CHECK_COUNT(GetBinary)
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    CHECK_INSTANCE
    ModelData *d = &in->d;
    if (nValues != nvr) return refuse(in, "fmi3SetBinary: scalars only");
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] != VR_BIN_P) return refuse(in, "only bin_p can be set as Binary");
        if (!settable(in, vr[i])) return refuse(in, "a fixed parameter is set only before initialization ends");
        if (valueSizes[i] > TEXT_BYTES - 1 || (valueSizes[i] > 0 && values[i] == NULL))
            return refuse(in, "bin_p: at most 63 bytes");
        memcpy(d->bin_p, values[i], valueSizes[i]);
        d->bin_p_size = valueSizes[i];
        k++;
    }
    return fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    return nvr == 0 ? fmi3OK : refuse((Instance *)instance, "no clocks");
}

#undef CHECK_INSTANCE
#undef CHECK_COUNT
#undef GET_ONE
#undef SET_ONE

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
    return refuse((Instance *)instance, "no configuration mode: n_y keeps its start value");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return refuse((Instance *)instance, "no configuration mode: n_y keeps its start value");
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
    return s;
}

/* ---- Scheduled execution: not this FMU's interface ---- */

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    return refuse((Instance *)instance, "co-simulation only");
}
