/* Runs a prepared list of FMI 2.0 calls in one go, so that a co-simulation step costs one
 * crossing from Python into C per group of FMU calls instead of one per call. */
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
        if (status > 1) {
            *failed = i;
            return status;
        }
    }
    return 0;
}
