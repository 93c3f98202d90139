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
#include <sched.h>
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
    long skip;    /* waits left without polling */
    long backoff; /* waits skipped after the next failed poll */
} Spin;

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
    int op;                /* the request (OP_*) */
    long request_seq;      /* requests posted by the master */
    long reply_seq;        /* requests answered by the worker */
    long seen;             /* the worker's last request taken */
    int worker_sleeping;   /* the worker waits on the request pipe: a request writes a byte there */
    int master_sleeping;   /* the master waits on the reply pipe: a reply writes a byte there */
    Spin worker_spin;
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
    s->worker_sleeping = 1; /* until it first serves */
}

/* Both sides wait for the other by polling the sequence numbers for a few microseconds (a step
 * of the rest of the loop takes that long; the other side runs on the other core), then sleep on
 * their pipe; the other side writes a byte there only when it sees the sleeping flag. A side
 * whose polls keep failing (a loaded machine: the other side waits for a core) polls less and
 * less often, so that it never burns a core for nothing. */
#define SPIN_NS 20000L
#define BACKOFF_LIMIT 4096
#define LOAD(x) __atomic_load_n(&(x), __ATOMIC_SEQ_CST)
#define STORE(x, v) __atomic_store_n(&(x), (v), __ATOMIC_SEQ_CST)

static long now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long)ts.tv_sec * 1000000000L + ts.tv_nsec;
}

static int spin_until(Spin *spin, volatile long *seq, long value) {
    long start;
    if (spin->skip > 0) {
        spin->skip--;
        return LOAD(*seq) == value;
    }
    start = now_ns();
    do {
        int k;
        for (k = 0; k < 64; k++) {
            if (LOAD(*seq) == value) {
                spin->backoff = 0;
                return 1;
            }
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#endif
        }
    } while (now_ns() - start < SPIN_NS);
    spin->backoff = spin->backoff ? (spin->backoff * 2 > BACKOFF_LIMIT ? BACKOFF_LIMIT : spin->backoff * 2) : 1;
    spin->skip = spin->backoff;
    return 0;
}

/* ------------------------------------------------------------------ the master's side */
typedef struct {
    Shared *shared;
    int request_fd; /* write end of the request pipe */
    int reply_fd;   /* read end of the reply pipe */
    int watchdog_ms; /* wall time a request may take; 0: no limit */
    int failure;    /* FAILURE_*: set once, then every call fails */
    int function;   /* the FMI function of the request that failed */
    int wake_fd;    /* read end of the process's signal wake-up pipe, or -1 */
    Spin spin;
} Proxy;

__attribute__((visibility("default"))) long proxy_size(void) { return (long)sizeof(Proxy); }

/* Posts a request; 0, or -1 when the worker is gone. */
__attribute__((visibility("default"))) int proxy_post(Proxy *p, int op) {
    Shared *s = p->shared;
    unsigned char byte = (unsigned char)op;
    s->op = op;
    STORE(s->request_seq, s->request_seq + 1);
    if (LOAD(s->worker_sleeping)) {
        ssize_t done;
        do {
            done = write(p->request_fd, &byte, 1);
        } while (done < 0 && errno == EINTR);
        if (done != 1) return -1;
    }
    return 0;
}

/* Sends a request and waits for its reply: the worker's status, or Fatal with p->failure set
 * when the worker ended, outlasted the watchdog, or a signal arrived (Python then raises it). */
__attribute__((visibility("default"))) int proxy_request(Proxy *p, int op, int function) {
    Shared *s = p->shared;
    struct pollfd fds[2];
    long deadline, seq;
    if (p->failure) return FMI_FATAL;
    p->function = function;
    deadline = p->watchdog_ms > 0 ? now_ns() / 1000000L + p->watchdog_ms : 0;
    if (proxy_post(p, op) < 0) {
        p->failure = FAILURE_ENDED;
        return FMI_FATAL;
    }
    seq = s->request_seq;
    if (p->wake_fd < 0 || !spin_until(&p->spin, &s->reply_seq, seq)) { /* no spin unless a signal can wake the poll */
        for (;;) {
            int wait = -1, ready;
            STORE(s->master_sleeping, 1);
            if (LOAD(s->reply_seq) == seq) break;
            if (deadline) {
                long left = deadline - now_ns() / 1000000L;
                wait = left > 0 ? (int)left : 0;
            }
            fds[0].fd = p->reply_fd;
            fds[0].events = POLLIN;
            fds[0].revents = 0;
            fds[1].fd = p->wake_fd;
            fds[1].events = POLLIN;
            fds[1].revents = 0;
            ready = poll(fds, p->wake_fd >= 0 ? 2 : 1, wait);
            if ((ready < 0 && errno == EINTR) || (ready > 0 && fds[1].revents)) {
                unsigned char bytes[64]; /* the signal's byte, taken: the next request starts clean */
                if (p->wake_fd >= 0 && read(p->wake_fd, bytes, sizeof bytes) < 0) {
                }
                p->failure = FAILURE_INTERRUPTED;
                break;
            }
            if (ready == 0) {
                p->failure = FAILURE_WATCHDOG;
                break;
            }
            if (ready > 0 && (fds[0].revents & POLLIN)) {
                unsigned char bytes[64];
                ssize_t done = read(p->reply_fd, bytes, sizeof bytes);
                if (done == 0) {
                    p->failure = FAILURE_ENDED;
                    break;
                }
            } else if (ready > 0 && (fds[0].revents & (POLLHUP | POLLERR))) {
                p->failure = FAILURE_ENDED;
                break;
            }
        }
        STORE(s->master_sleeping, 0);
        if (p->failure && LOAD(s->reply_seq) != seq) return FMI_FATAL;
        p->failure = FAILURE_NONE;
    }
    if (FAILED(s->status)) p->function = s->function;
    return s->status;
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

/* Waits for the next request: its op, or 0 when the master is gone. */
static int next_request(Shared *s, int request_fd) {
    long seen = s->seen;
    for (;;) {
        unsigned char bytes[64];
        ssize_t done;
        if (spin_until(&s->worker_spin, &s->request_seq, seen + 1)) break;
        STORE(s->worker_sleeping, 1);
        if (LOAD(s->request_seq) != seen) {
            STORE(s->worker_sleeping, 0);
            break;
        }
        do {
            done = read(request_fd, bytes, sizeof bytes);
        } while (done < 0 && errno == EINTR);
        STORE(s->worker_sleeping, 0);
        if (done <= 0) return 0;
        if (LOAD(s->request_seq) != seen) break;
    }
    s->seen = seen + 1;
    return s->op;
}

static void reply(Shared *s, int reply_fd) {
    unsigned char byte = 1;
    STORE(s->reply_seq, s->seen);
    if (LOAD(s->master_sleeping)) {
        if (write(reply_fd, &byte, 1) < 0) { /* the master is gone: the next read says so */
        }
    }
}

/* Runs requests until one only Python does (returns OP_PYTHON) or the master is gone (returns 0);
 * with no component, only waits for the first request (Python's). */
__attribute__((visibility("default"))) int serve(Shared *s, int request_fd, int reply_fd, SetReal set, GetReal get,
                                                 DoStep step, void *component) {
    for (;;) {
        int status = 0, got, op = next_request(s, request_fd);
        if (op == 0 || op == OP_PYTHON || component == NULL) return op;
        status = apply_sets(s, set, component);
        if (!FAILED(status) && op == OP_GET) {
            got = get(component, GET_VR(s), (size_t)s->nget, GET_VAL(s));
            s->prefetched = !FAILED(got);
            s->prefetch_status = got;
            if (FAILED(got)) s->function = FUNCTION_GET;
            status = got > status || FAILED(got) ? got : status;
        } else if (!FAILED(status) && op == OP_STEP) {
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
        reply(s, reply_fd);
    }
}
