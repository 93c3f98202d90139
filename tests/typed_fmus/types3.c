/* An FMI 3.0 Co-Simulation model with a variable of every FMI 3.0 numeric type, for the tests:
 * Float64, Float32, Int8 to UInt64, Boolean and Enumeration inputs and outputs, arrays (an input
 * vector, an output vector and a 2 x 2 output matrix), String and Binary parameters, and a state
 * that changes at events (a counter that steps each time an integrator crosses a threshold).
 *
 * Per doStep(t, h), from the inputs set before it:
 *   x += gain u h while enable; when x >= threshold: counter += 1 and x -= threshold (the event);
 *   f32_acc += f32_in h (in single precision); each integer output = its input + counter;
 *   above = counter odd; mode_out = mode; w += v h; m = [[x, counter], [w_1, -x]]; steps += 1;
 *   terminateSimulation once the counter reaches stop_count (when above 0). A UInt16 input of
 *   65535 is refused (fmi3Error).
 * Outputs depend on the state only (no direct feedthrough). */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

typedef struct {
    double u, x, gain, threshold;
    int32_t counter;
    float f32_in, f32_acc;
    int8_t i8_in, i8_out;
    uint8_t u8_in, u8_out;
    int16_t i16_in, i16_out;
    uint16_t u16_in, u16_out;
    int32_t i32_in, i32_out;
    uint32_t u32_in, u32_out;
    int64_t i64_in, i64_out;
    uint64_t u64_in, u64_out, steps;
    int32_t stop_count; /* > 0: the FMU asks to end the simulation when the counter reaches it */
    bool enable, above;
    int64_t mode, mode_out;
    double v[3], w[3], m[4];
    char label[64];
    uint8_t key[16];
    size_t key_size;
} Model;

static void defaults(Model *m) {
    memset(m, 0, sizeof *m);
    m->gain = 1.0;
    m->threshold = 0.05;
    m->enable = true;
    m->mode = m->mode_out = 1;
    strcpy(m->label, "plain");
    m->key[0] = 0xab;
    m->key_size = 1;
}

static void settle(Model *m) {
    m->above = m->counter % 2 == 1;
    m->m[0] = m->x;
    m->m[1] = m->counter;
    m->m[2] = m->w[0];
    m->m[3] = -m->x;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean event_mode,
                                         fmi3Boolean early_return, const fmi3ValueReference required[],
                                         size_t n_required, fmi3InstanceEnvironment environment,
                                         fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update) {
    Model *m;
    (void)name, (void)resources, (void)visible, (void)logging, (void)event_mode, (void)early_return;
    (void)required, (void)n_required, (void)update;
    if (strcmp(token, "{quadcosim-types3}") != 0) {
        if (log) log(environment, fmi3Error, "error", "wrong instantiation token");
        return NULL;
    }
    m = calloc(1, sizeof *m);
    defaults(m);
    return m;
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }
const char *fmi3GetVersion(void) { return fmi3Version; }
fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String categories[]) {
    (void)c, (void)on, (void)n, (void)categories;
    return fmi3OK;
}
fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    (void)c, (void)tolerance_defined, (void)tolerance, (void)start, (void)stop_defined, (void)stop;
    return fmi3OK;
}
fmi3Status fmi3ExitInitializationMode(fmi3Instance c) { settle(c); return fmi3OK; }
fmi3Status fmi3Terminate(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3Reset(fmi3Instance c) { defaults(c); return fmi3OK; }

/* The address and element count of variable vr as type code `type`, or NULL. */
enum { F64, F32, I8, U8, I16, U16, I32, U32, I64, U64, BOOL };

static void *where(Model *m, fmi3ValueReference vr, int type, size_t *count) {
    *count = 1;
    switch (vr) {
    case 1: return type == F64 ? &m->u : NULL;
    case 2: return type == F64 ? &m->x : NULL;
    case 3: return type == I32 ? &m->counter : NULL;
    case 4: return type == F64 ? &m->gain : NULL;
    case 5: return type == F64 ? &m->threshold : NULL;
    case 6: return type == F32 ? &m->f32_in : NULL;
    case 7: return type == F32 ? &m->f32_acc : NULL;
    case 8: return type == I8 ? &m->i8_in : NULL;
    case 9: return type == I8 ? &m->i8_out : NULL;
    case 10: return type == U8 ? &m->u8_in : NULL;
    case 11: return type == U8 ? &m->u8_out : NULL;
    case 12: return type == I16 ? &m->i16_in : NULL;
    case 13: return type == I16 ? &m->i16_out : NULL;
    case 14: return type == U16 ? &m->u16_in : NULL;
    case 15: return type == U16 ? &m->u16_out : NULL;
    case 16: return type == I32 ? &m->i32_in : NULL;
    case 17: return type == I32 ? &m->i32_out : NULL;
    case 18: return type == U32 ? &m->u32_in : NULL;
    case 19: return type == U32 ? &m->u32_out : NULL;
    case 20: return type == I64 ? &m->i64_in : NULL;
    case 21: return type == I64 ? &m->i64_out : NULL;
    case 22: return type == U64 ? &m->u64_in : NULL;
    case 23: return type == U64 ? &m->u64_out : NULL;
    case 24: return type == BOOL ? &m->enable : NULL;
    case 25: return type == BOOL ? &m->above : NULL;
    case 26: return type == I64 ? &m->mode : NULL;
    case 27: return type == I64 ? &m->mode_out : NULL;
    case 28: *count = 3; return type == F64 ? m->v : NULL;
    case 29: *count = 3; return type == F64 ? m->w : NULL;
    case 30: *count = 4; return type == F64 ? m->m : NULL;
    case 33: return type == U64 ? &m->steps : NULL;
    case 34: return type == I32 ? &m->stop_count : NULL;
    default: return NULL;
    }
}

/* The model refuses a UInt16 input of 65535 (for the tests of a refused set). */
static int refused(int code, const void *value) { return code == U16 && *(const uint16_t *)value == UINT16_MAX; }

#define ACCESS(Type, type, code)                                                                             \
    fmi3Status fmi3Get##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t n, type v[], size_t nv) {   \
        size_t k, at = 0, count;                                                                             \
        for (k = 0; k < n; k++) {                                                                            \
            type *p = where(c, vr[k], code, &count);                                                         \
            if (p == NULL || at + count > nv) return fmi3Error;                                              \
            memcpy(v + at, p, count * sizeof(type));                                                         \
            at += count;                                                                                     \
        }                                                                                                    \
        return at == nv ? fmi3OK : fmi3Error;                                                                \
    }                                                                                                        \
    fmi3Status fmi3Set##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const type v[],         \
                             size_t nv) {                                                                    \
        size_t k, at = 0, count;                                                                             \
        for (k = 0; k < n; k++) {                                                                            \
            type *p = where(c, vr[k], code, &count);                                                         \
            if (p == NULL || at + count > nv || refused(code, v + at)) return fmi3Error;                     \
            memcpy(p, v + at, count * sizeof(type));                                                         \
            at += count;                                                                                     \
        }                                                                                                    \
        return at == nv ? fmi3OK : fmi3Error;                                                                \
    }
ACCESS(Float64, fmi3Float64, F64)
ACCESS(Float32, fmi3Float32, F32)
ACCESS(Int8, fmi3Int8, I8)
ACCESS(UInt8, fmi3UInt8, U8)
ACCESS(Int16, fmi3Int16, I16)
ACCESS(UInt16, fmi3UInt16, U16)
ACCESS(Int32, fmi3Int32, I32)
ACCESS(UInt32, fmi3UInt32, U32)
ACCESS(Int64, fmi3Int64, I64)
ACCESS(UInt64, fmi3UInt64, U64)
ACCESS(Boolean, fmi3Boolean, BOOL)

fmi3Status fmi3GetString(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3String v[], size_t nv) {
    Model *m = c;
    if (n != nv) return fmi3Error;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != 31) return fmi3Error;
        v[k] = m->label;
    }
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3String v[],
                         size_t nv) {
    Model *m = c;
    if (n != nv) return fmi3Error;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != 31 || strlen(v[k]) >= sizeof m->label) return fmi3Error;
        strcpy(m->label, v[k]);
    }
    return fmi3OK;
}

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t n, size_t sizes[],
                         fmi3Binary v[], size_t nv) {
    Model *m = c;
    if (n != nv) return fmi3Error;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != 32) return fmi3Error;
        sizes[k] = m->key_size;
        v[k] = m->key;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const size_t sizes[],
                         const fmi3Binary v[], size_t nv) {
    Model *m = c;
    if (n != nv) return fmi3Error;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != 32 || sizes[k] > sizeof m->key) return fmi3Error;
        memcpy(m->key, v[k], sizes[k]);
        m->key_size = sizes[k];
    }
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_set_prior,
                      fmi3Boolean *event_needed, fmi3Boolean *terminate, fmi3Boolean *early, fmi3Float64 *last) {
    Model *m = c;
    (void)no_set_prior;
#ifdef LYING_STEP /* the tests' liar: from t = 0.1 s its step returns -1, which is no FMI status */
    if (t >= 0.1 - 1e-9)
        return (fmi3Status)-1;
#endif
#ifdef CRASHING_STEP /* the tests' crash: at t = 0.1 s its step writes through a null pointer */
    if (t >= 0.1 - 1e-9) {
        volatile int *volatile nowhere = NULL;
        *nowhere = 1;
    }
#endif
    if (m->enable)
        m->x += m->gain * m->u * h;
    if (m->x >= m->threshold) {
        m->counter += 1;
        m->x -= m->threshold;
    }
    m->f32_acc += m->f32_in * (float)h;
    m->i8_out = (int8_t)(m->i8_in + m->counter);
    m->u8_out = (uint8_t)(m->u8_in + m->counter);
    m->i16_out = (int16_t)(m->i16_in + m->counter);
    m->u16_out = (uint16_t)(m->u16_in + m->counter);
    m->i32_out = m->i32_in + m->counter;
    m->u32_out = m->u32_in + (uint32_t)m->counter;
    m->i64_out = m->i64_in + m->counter;
    m->u64_out = m->u64_in + (uint64_t)m->counter;
    m->mode_out = m->mode;
    for (int k = 0; k < 3; k++)
        m->w[k] += m->v[k] * h;
    m->steps += 1;
    settle(m);
    *event_needed = false;
    *terminate = m->stop_count > 0 && m->counter >= m->stop_count;
    *early = false;
    *last = t + h;
    return fmi3OK;
}
