/* An FMU in a worker process, seen by the master as FMI 2.0 functions.
 *
 * The master's side (proxy_*) has the signatures of fmi2SetReal, fmi2GetReal and fmi2DoStep,
 * so that the call runner calls them as it calls an FMU loaded in process; the component it
 * passes is a Proxy. Values travel through a shared mapping (a Shared header and its arrays);
 * a request is one byte on a pipe to the worker, its reply one byte back. Inputs set are kept
 * in the mapping and applied by the worker with the next request; after a step the worker reads
 * the outputs last asked for, so that the next fmi2GetReal of them costs no crossing: a macro
 * step costs one round trip (two when inputs are set between the step and the read).
 *
 * The worker's side (serve) runs the requests on the FMU's own functions until the master asks
 * for something only Python does (set-up, reset, its log, the end). */
#define _POSIX_C_SOURCE 200809L /* poll, clock_gettime under -std=c99 */
#include <errno.h>
#include <poll.h>
#include <stddef.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef int (*SetReal)(void *, const unsigned int *, size_t, const double *);
typedef int (*GetReal)(void *, const unsigned int *, size_t, double *);
typedef int (*DoStep)(void *, double, double, int);

enum { OP_SET = 1, OP_GET = 2, OP_STEP = 3, OP_PYTHON = 4 };
enum { FAILURE_NONE = 0, FAILURE_ENDED = 1, FAILURE_WATCHDOG = 2, FAILURE_INTERRUPTED = 3 };
enum { FUNCTION_SET = 0, FUNCTION_GET = 1, FUNCTION_STEP = 2 };

#define FMI_FATAL 4
#define FAILED(status) ((unsigned int)(status) > 1u) /* Error, Fatal, Pending, or no status at all */

typedef struct {
    long capacity;         /* values each array holds */
    long nset;             /* inputs set and not yet applied */
    long nget;             /* outputs last asked for */
    int prefetched;        /* get_val holds their present values */
    int prefetch_status;   /* status of the fmi2GetReal that read them */
    int status;            /* reply: worst status of the request */
    int function;          /* reply: the FMI function that failed (FUNCTION_*) */
    double t, h;           /* fmi2DoStep's arguments */
    int no_set_prior;
    int pad;
    /* then: unsigned int set_vr[capacity]; unsigned int get_vr[capacity];
     *       double set_val[capacity]; double get_val[capacity]; */
} Shared;

#define SET_VR(s) ((unsigned int *)((char *)(s) + sizeof(Shared)))
#define GET_VR(s) (SET_VR(s) + (s)->capacity)
#define SET_VAL(s) ((double *)((char *)(s) + sizeof(Shared) + 8 * (((s)->capacity + 1) / 2 * 2)))
#define GET_VAL(s) (SET_VAL(s) + (s)->capacity)

__attribute__((visibility("default"))) long shared_size(long capacity) {
    return (long)sizeof(Shared) + 8 * ((capacity + 1) / 2 * 2) + 16 * capacity;
}

__attribute__((visibility("default"))) void shared_init(Shared *s, long capacity) {
    memset(s, 0, sizeof(Shared));
    s->capacity = capacity;
}

/* ------------------------------------------------------------------ the master's side */
typedef struct {
    Shared *shared;
    int request_fd; /* write end of the request pipe */
    int reply_fd;   /* read end of the reply pipe */
    int watchdog_ms; /* wall time a request may take; 0: no limit */
    int failure;    /* FAILURE_*: set once, then every call fails */
    int function;   /* the FMI function of the request that failed */
} Proxy;

__attribute__((visibility("default"))) long proxy_size(void) { return (long)sizeof(Proxy); }

static long now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/* Sends a request and waits for its reply: the worker's status, or Fatal with p->failure set
 * when the worker ended, outlasted the watchdog, or a signal arrived (Python then raises it). */
__attribute__((visibility("default"))) int proxy_request(Proxy *p, int op, int function) {
    unsigned char byte = (unsigned char)op;
    struct pollfd fd;
    long deadline = p->watchdog_ms > 0 ? now_ms() + p->watchdog_ms : 0;
    ssize_t done;
    if (p->failure) return FMI_FATAL;
    p->function = function;
    do {
        done = write(p->request_fd, &byte, 1);
    } while (done < 0 && errno == EINTR);
    if (done != 1) {
        p->failure = FAILURE_ENDED;
        return FMI_FATAL;
    }
    for (;;) {
        int wait = -1, ready;
        if (deadline) {
            long left = deadline - now_ms();
            wait = left > 0 ? (int)left : 0;
        }
        fd.fd = p->reply_fd;
        fd.events = POLLIN;
        fd.revents = 0;
        ready = poll(&fd, 1, wait);
        if (ready < 0 && errno == EINTR) {
            p->failure = FAILURE_INTERRUPTED;
            return FMI_FATAL;
        }
        if (ready == 0) {
            p->failure = FAILURE_WATCHDOG;
            return FMI_FATAL;
        }
        if (ready > 0) break;
    }
    do {
        done = read(p->reply_fd, &byte, 1);
    } while (done < 0 && errno == EINTR);
    if (done != 1) { /* end of file: the worker is gone */
        p->failure = FAILURE_ENDED;
        return FMI_FATAL;
    }
    if (FAILED(p->shared->status)) p->function = p->shared->function;
    return p->shared->status;
}

__attribute__((visibility("default"))) int proxy_set_real(Proxy *p, const unsigned int *vr, size_t n,
                                                          const double *values) {
    Shared *s = p->shared;
    if (p->failure) return FMI_FATAL;
    if ((long)n > s->capacity) return 3;
    if (s->nset + (long)n > s->capacity) { /* full: apply what is kept first */
        int status = proxy_request(p, OP_SET, FUNCTION_SET);
        if (FAILED(status)) return status;
    }
    memcpy(SET_VR(s) + s->nset, vr, n * sizeof(unsigned int));
    memcpy(SET_VAL(s) + s->nset, values, n * sizeof(double));
    s->nset += (long)n;
    s->prefetched = 0;
    return 0;
}

__attribute__((visibility("default"))) int proxy_get_real(Proxy *p, const unsigned int *vr, size_t n,
                                                          double *values) {
    Shared *s = p->shared;
    int status;
    if (p->failure) return FMI_FATAL;
    if ((long)n > s->capacity) return 3;
    if (s->prefetched && s->nset == 0 && (long)n == s->nget && memcmp(vr, GET_VR(s), n * sizeof(unsigned int)) == 0) {
        memcpy(values, GET_VAL(s), n * sizeof(double));
        return s->prefetch_status;
    }
    memcpy(GET_VR(s), vr, n * sizeof(unsigned int));
    s->nget = (long)n;
    status = proxy_request(p, OP_GET, FUNCTION_GET);
    if (!FAILED(status)) memcpy(values, GET_VAL(s), n * sizeof(double));
    return status;
}

__attribute__((visibility("default"))) int proxy_do_step(Proxy *p, double t, double h, int no_set_prior) {
    Shared *s = p->shared;
    if (p->failure) return FMI_FATAL;
    s->t = t;
    s->h = h;
    s->no_set_prior = no_set_prior;
    return proxy_request(p, OP_STEP, FUNCTION_STEP);
}

/* ------------------------------------------------------------------ the worker's side */
static int apply_sets(Shared *s, SetReal set, void *component) {
    int status = 0;
    if (s->nset) {
        status = set(component, SET_VR(s), (size_t)s->nset, SET_VAL(s));
        s->nset = 0;
        if (FAILED(status)) s->function = FUNCTION_SET;
    }
    return status;
}

/* Runs requests until one only Python does (returns OP_PYTHON) or the master is gone (returns 0). */
__attribute__((visibility("default"))) int serve(Shared *s, int request_fd, int reply_fd, SetReal set, GetReal get,
                                                 DoStep step, void *component) {
    for (;;) {
        unsigned char byte;
        ssize_t done;
        int status = 0, got;
        do {
            done = read(request_fd, &byte, 1);
        } while (done < 0 && errno == EINTR);
        if (done != 1) return 0;
        if (byte == OP_PYTHON) return OP_PYTHON;
        status = apply_sets(s, set, component);
        if (!FAILED(status) && byte == OP_GET) {
            got = get(component, GET_VR(s), (size_t)s->nget, GET_VAL(s));
            s->prefetched = !FAILED(got);
            s->prefetch_status = got;
            if (FAILED(got)) s->function = FUNCTION_GET;
            status = got > status || FAILED(got) ? got : status;
        } else if (!FAILED(status) && byte == OP_STEP) {
            s->prefetched = 0;
            status = step(component, s->t, s->h, s->no_set_prior);
            if (FAILED(status)) {
                s->function = FUNCTION_STEP;
            } else if (s->nget) { /* the outputs the master reads next, read now */
                got = get(component, GET_VR(s), (size_t)s->nget, GET_VAL(s));
                s->prefetched = !FAILED(got);
                s->prefetch_status = got;
            }
        }
        s->status = status;
        do {
            done = write(reply_fd, &byte, 1);
        } while (done < 0 && errno == EINTR);
        if (done != 1) return 0;
    }
}
