/* FMI calls of any variable type behind the three signatures of the call runner (calls.c):
 * set(context, vr, n, values), get(context, vr, n, values) and step(context, t, h, flag).
 *
 * The master's bus holds every signal as a double. A typed call converts between the bus and
 * the FMU's own type (FMI 2.0 Integer, Boolean, Enumeration; FMI 3.0 Float32/64, the integer
 * types, Boolean, Enumeration) in a preallocated scratch buffer, and calls the FMU's setter or
 * getter once per type; a value is read from, or written to, its own bus address, so that an
 * FMI 3.0 array is set whole whatever slots its elements come from. The runner's own vr, n and
 * values arguments are not used: the context holds them. */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum {
    T_F64 = 0, T_F32 = 1, T_I8 = 2, T_U8 = 3, T_I16 = 4, T_U16 = 5, T_I32 = 6, T_U32 = 7, T_I64 = 8, T_U64 = 9,
    T_BOOL = 10,     /* fmi3Boolean: a C bool */
    T_INT2 = 11,     /* fmi2Integer and an FMI 2.0 Enumeration: an int */
    T_BOOL2 = 12     /* fmi2Boolean: an int, 0 or 1 */
};

typedef struct {
    void *function;          /* the FMU's fmi2Set/GetX or fmi3Set/GetX */
    void *instance;
    int type;
    int fmi3;                /* 1: the FMI 3.0 signature, with the number of values last */
    const unsigned int *vr;
    size_t nvr;
    size_t nvalues;          /* values (an FMI 3.0 array counts its elements) */
    double *const *where;    /* the bus address of each value */
    void *scratch;           /* nvalues of the FMU's type */
} Group;

typedef struct {
    const Group *groups;
    long count;
    long failed;             /* out: the group whose call failed */
} Typed;

typedef int (*Call2)(void *, const unsigned int *, size_t, void *);
typedef int (*Call3)(void *, const unsigned int *, size_t, void *, size_t);

/* x rounded to the nearest integer, held in [lo, hi]; NaN gives lo (the bus check reports it). */
static double held(double x, double lo, double hi) {
    x = round(x);
    if (!(x >= lo))
        return lo;
    return x > hi ? hi : x;
}

static void to_fmu(const Group *g) {
    size_t k;
    for (k = 0; k < g->nvalues; k++) {
        double x = *g->where[k];
        switch (g->type) {
        case T_F64: ((double *)g->scratch)[k] = x; break;
        case T_F32: ((float *)g->scratch)[k] = (float)x; break;
        case T_I8: ((int8_t *)g->scratch)[k] = (int8_t)held(x, INT8_MIN, INT8_MAX); break;
        case T_U8: ((uint8_t *)g->scratch)[k] = (uint8_t)held(x, 0, UINT8_MAX); break;
        case T_I16: ((int16_t *)g->scratch)[k] = (int16_t)held(x, INT16_MIN, INT16_MAX); break;
        case T_U16: ((uint16_t *)g->scratch)[k] = (uint16_t)held(x, 0, UINT16_MAX); break;
        case T_I32: case T_INT2: ((int32_t *)g->scratch)[k] = (int32_t)held(x, INT32_MIN, INT32_MAX); break;
        case T_U32: ((uint32_t *)g->scratch)[k] = (uint32_t)held(x, 0, UINT32_MAX); break;
        case T_I64:  /* 2^63 is the first double out of range */
            x = round(x);
            ((int64_t *)g->scratch)[k] = !(x >= -9223372036854775808.0) ? INT64_MIN
                                         : x >= 9223372036854775808.0 ? INT64_MAX : (int64_t)x;
            break;
        case T_U64:
            x = round(x);
            ((uint64_t *)g->scratch)[k] = !(x >= 0.0) ? 0 : x >= 18446744073709551616.0 ? UINT64_MAX : (uint64_t)x;
            break;
        case T_BOOL: ((bool *)g->scratch)[k] = x != 0.0; break;
        default: ((int32_t *)g->scratch)[k] = x != 0.0; break; /* T_BOOL2 */
        }
    }
}

static void from_fmu(const Group *g) {
    size_t k;
    for (k = 0; k < g->nvalues; k++) {
        double x;
        switch (g->type) {
        case T_F64: x = ((double *)g->scratch)[k]; break;
        case T_F32: x = ((float *)g->scratch)[k]; break;
        case T_I8: x = ((int8_t *)g->scratch)[k]; break;
        case T_U8: x = ((uint8_t *)g->scratch)[k]; break;
        case T_I16: x = ((int16_t *)g->scratch)[k]; break;
        case T_U16: x = ((uint16_t *)g->scratch)[k]; break;
        case T_I32: case T_INT2: x = ((int32_t *)g->scratch)[k]; break;
        case T_U32: x = ((uint32_t *)g->scratch)[k]; break;
        case T_I64: x = (double)((int64_t *)g->scratch)[k]; break;
        case T_U64: x = (double)((uint64_t *)g->scratch)[k]; break;
        case T_BOOL: x = ((bool *)g->scratch)[k] ? 1.0 : 0.0; break;
        default: x = ((int32_t *)g->scratch)[k] ? 1.0 : 0.0; break; /* T_BOOL2: any non-zero is true */
        }
        *g->where[k] = x;
    }
}

static int call(const Group *g) {
    if (g->fmi3)
        return ((Call3)g->function)(g->instance, g->vr, g->nvr, g->scratch, g->nvalues);
    return ((Call2)g->function)(g->instance, g->vr, g->nvr, g->scratch);
}

/* The worst status; on one above Warning, stops with the failing group in context->failed. */
__attribute__((visibility("default"))) int typed_set(void *context, const unsigned int *vr, size_t n,
                                                     double *values) {
    Typed *c = (Typed *)context;
    long i;
    int status, worst = 0;
    (void)vr, (void)n, (void)values;
    for (i = 0; i < c->count; i++) {
        to_fmu(&c->groups[i]);
        status = call(&c->groups[i]);
        if ((unsigned int)status > 1u) { /* -1, or any number that is no FMI status, is a failure */
            c->failed = i;
            return status;
        }
        worst = status > worst ? status : worst;
    }
    return worst;
}

__attribute__((visibility("default"))) int typed_get(void *context, const unsigned int *vr, size_t n,
                                                     double *values) {
    Typed *c = (Typed *)context;
    long i;
    int status, worst = 0;
    (void)vr, (void)n, (void)values;
    for (i = 0; i < c->count; i++) {
        status = call(&c->groups[i]);
        if ((unsigned int)status > 1u) { /* -1, or any number that is no FMI status, is a failure */
            c->failed = i;
            return status;
        }
        from_fmu(&c->groups[i]);
        worst = status > worst ? status : worst;
    }
    return worst;
}

/* ------------------------------------------------------------------ FMI 3.0 doStep */
typedef int (*DoStep3)(void *, double, double, bool, bool *, bool *, bool *, double *);

typedef struct {
    void *function;          /* fmi3DoStep */
    void *instance;
    int terminated;          /* out: the FMU set terminateSimulation */
    int early;               /* out: it returned early (not allowed: the master asked for none) */
    double last;             /* out: lastSuccessfulTime */
} Step3;

/* STEP3_TERMINATED: a status above any FMI status, for the FMU's request to end the run. */
enum { STEP3_TERMINATED = 6 };

__attribute__((visibility("default"))) int step3(void *context, double t, double h, int flag) {
    Step3 *s = (Step3 *)context;
    bool event = false, terminate = false, early = false;
    int status = ((DoStep3)s->function)(s->instance, t, h, flag != 0, &event, &terminate, &early, &s->last);
    s->terminated = terminate;
    s->early = early;
    if ((unsigned int)status > 1u)
        return status;
    return terminate || early ? STEP3_TERMINATED : status;
}
