/* Runs a prepared list of FMI 2.0 calls in one go, so that a co-simulation step costs one
 * crossing from Python into C per group of FMU calls instead of one per call. */
#include <math.h>
#include <stddef.h>

typedef int (*SetReal)(void *, const unsigned int *, size_t, const double *);
typedef int (*GetReal)(void *, const unsigned int *, size_t, double *);
typedef int (*DoStep)(void *, double, double, int);

enum { CALL_SET_REAL = 0, CALL_GET_REAL = 1, CALL_DO_STEP = 2 };

typedef struct {
    int kind;
    void *function;
    void *component;
    const unsigned int *vr;
    size_t n;
    double *values;
    double h;
} Call;

/* Returns the worst status; on a status above fmi2Warning, stops and stores the index of
 * the failing call in *failed. */
__attribute__((visibility("default"))) int run_calls(const Call *calls, int count, double t, int *failed) {
    int i, status;
    for (i = 0; i < count; i++) {
        const Call *c = &calls[i];
        switch (c->kind) {
        case CALL_SET_REAL:
            status = ((SetReal)c->function)(c->component, c->vr, c->n, c->values);
            break;
        case CALL_GET_REAL:
            status = ((GetReal)c->function)(c->component, c->vr, c->n, c->values);
            break;
        default:
            status = ((DoStep)c->function)(c->component, t, c->h, 1);
            break;
        }
        if ((unsigned int)status > 1u) { /* -1, or any number that is no FMI status, is a failure */
            *failed = i;
            return status;
        }
    }
    return 0;
}

/* ------------------------------------------------------------------ the chunk runner
 * Runs whole macro steps: a program of operations per step (FMI calls, compiled blocks, table
 * rows, the recording and the non-finite check) from step n to a given end, returning to
 * Python only at the end of the chunk, at an operation only Python can do (a Python block, a
 * fault), or at once on a failure with the step and the operation. The program is resumable:
 * it keeps the step and the operation it stopped at. */
typedef int (*BlockStep)(double, const double *, double *, double *);

enum {
    OP_SET_REAL = 0, OP_GET_REAL = 1, OP_DO_STEP = 2, /* as CALL_* */
    OP_BLOCK = 3,   /* a compiled block: gather its inputs, call its step */
    OP_TABLE = 4,   /* a table row (or a constant) copied onto the bus */
    OP_RECORD = 5,  /* record the bus every `decimation` steps, check it, stop after the last step */
    OP_PYTHON = 6   /* an operation Python runs: return to it */
};

enum { RUN_CHUNK_DONE = 0, RUN_PYTHON = 1, RUN_FINISHED = 2, RUN_NON_FINITE = 3, RUN_FMI_FAILED = 4,
       RUN_BLOCK_FAILED = 5 };

typedef struct {
    long into;   /* index in the destination vector */
    long source; /* index in the bus */
    long n;
} Gather;

typedef struct {
    int kind;
    int period;
    /* FMI calls, laid out as Call */
    void *function;
    void *component;
    const unsigned int *vr;
    size_t n;
    double *values;
    double h;
    /* compiled block */
    BlockStep step;
    double *u;
    double *y;
    double *data;
    const Gather *gather;
    long gathers;
    /* table: rows first_row .. first_row + rows - 1 of `width` values; the last row is held */
    const double *table;
    long first_row;
    long rows;
    long width;
} Op;

typedef struct {
    Op *ops;
    long count;
    double *bus;
    long bus_size;
    double *record;
    long record_width;
    const Gather *record_gather;
    long record_gathers;
    long decimation;
    double t0;
    double dt;
    long last;     /* the last step, `steps` */
    long n;        /* in/out: the present step */
    long op;       /* in/out: the next operation of the present step */
    long recorded; /* out: rows recorded */
    int status;    /* out: the FMI or block status of a failure */
    long record_first; /* the row record[0] holds: a streamed record holds a window of rows */
} Program;

static void gather(double *into, const double *bus, const Gather *g, long count) {
    long i, k;
    for (i = 0; i < count; i++)
        for (k = 0; k < g[i].n; k++)
            into[g[i].into + k] = bus[g[i].source + k];
}

static int finite_bus(const double *bus, long size) {
    long i;
    for (i = 0; i < size; i++)
        if (!isfinite(bus[i]))
            return 0;
    return 1;
}

static int run_op(Program *p, const Op *o, long n, double t) {
    long row;
    switch (o->kind) {
    case OP_SET_REAL:
        p->status = ((SetReal)o->function)(o->component, o->vr, o->n, o->values);
        return (unsigned int)p->status > 1u ? RUN_FMI_FAILED : -1;
    case OP_GET_REAL:
        p->status = ((GetReal)o->function)(o->component, o->vr, o->n, o->values);
        return (unsigned int)p->status > 1u ? RUN_FMI_FAILED : -1;
    case OP_DO_STEP:
        p->status = ((DoStep)o->function)(o->component, t, o->h, 1);
        return (unsigned int)p->status > 1u ? RUN_FMI_FAILED : -1;
    case OP_BLOCK:
        gather(o->u, p->bus, o->gather, o->gathers);
        p->status = o->step(t, o->u, o->y, o->data);
        return p->status != 0 ? RUN_BLOCK_FAILED : -1;
    case OP_TABLE:
        row = n / o->period - o->first_row;
        if (row >= o->rows)
            row = o->rows - 1;
        for (long k = 0; k < o->width; k++)
            o->y[k] = o->table[row * o->width + k];
        return -1;
    case OP_RECORD:
        if (n % p->decimation == 0) {
            gather(p->record + (n / p->decimation - p->record_first) * p->record_width, p->bus, p->record_gather,
                   p->record_gathers);
            p->recorded = n / p->decimation + 1;
            if (!finite_bus(p->bus, p->bus_size))
                return RUN_NON_FINITE;
        }
        return n == p->last ? RUN_FINISHED : -1;
    default:
        return RUN_PYTHON;
    }
}

/* Runs from step p->n, operation p->op, up to (not including) step `end`. On any return but
 * RUN_CHUNK_DONE and RUN_FINISHED, p->n and p->op name the step and the operation that stopped
 * it; after a RUN_PYTHON, the caller runs that operation and resumes at p->op + 1. */
__attribute__((visibility("default"))) int run_chunk(Program *p, long end) {
    long n, i;
    int code;
    for (n = p->n, i = p->op; n < end; n++, i = 0) {
        double t = p->t0 + (double)n * p->dt;
        for (; i < p->count; i++) {
            const Op *o = &p->ops[i];
            if (o->period > 1 && n % o->period != 0)
                continue;
            code = run_op(p, o, n, t);
            if (code >= 0) {
                p->n = n;
                p->op = i;
                return code;
            }
        }
    }
    p->n = end;
    p->op = 0;
    return RUN_CHUNK_DONE;
}
