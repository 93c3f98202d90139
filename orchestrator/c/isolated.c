/* An FMU in a worker process, seen by the master as the three C signatures of the call runner.
 *
 * The worker hosts the FMU's instance (FMI 2.0 or 3.0, of any variable type) and asks it, once
 * per run, for the C calls (quadcosim.orchestrator.fmi_types.CEntry) that set its inputs from, and write
 * its outputs to, float64 slots in a shared mapping, and for the call of its step. Each such
 * list of calls is a program, named by a number. The master's side (proxy_set, proxy_get,
 * proxy_step) has the signatures of fmi2SetReal, fmi2GetReal and fmi2DoStep; its first argument
 * is an Entry: the program and, for a set or get, the bus address of each value and its slot.
 *
 * A request is one byte on a pipe to the worker, its reply one byte back. Inputs set are kept in
 * the slots and applied by the worker with the next request; after a step the worker runs the
 * get programs the master has asked for, so that the next read of them costs no crossing: a macro
 * step costs one round trip (two when inputs are set between the step and the read).
 *
 * The worker's side (serve) runs the requests until the master asks for something only Python
 * does (set-up, a new program, reset, its log, the end). */
#define _POSIX_C_SOURCE 200809L /* poll, clock_gettime under -std=c99 */
#include <errno.h>
#include <poll.h>
#include <sched.h>
#include <stddef.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef int (*SetOrGet)(void *, const unsigned int *, size_t, double *);
typedef int (*DoStep)(void *, double, double, int);

enum { OP_SET = 1, OP_GET = 2, OP_STEP = 3, OP_PYTHON = 4 };
enum { FAILURE_NONE = 0, FAILURE_ENDED = 1, FAILURE_WATCHDOG = 2, FAILURE_INTERRUPTED = 3 };
enum { KIND_SET = 0, KIND_GET = 1, KIND_STEP = 2 };
#define MAX_PROGRAMS 256

#define FMI_FATAL 4
#define FAILED(status) ((unsigned int)(status) > 1u) /* Error, Fatal, Pending, or no status at all */

typedef struct {
    long skip;    /* waits left without polling */
    long backoff; /* waits skipped after the next failed poll */
} Spin;

typedef struct {
    long capacity;                       /* float64 slots */
    int npending;                        /* set programs waiting for the next request */
    int pending[MAX_PROGRAMS];           /* which */
    int wanted[MAX_PROGRAMS];            /* get programs run after each step */
    int prefetched[MAX_PROGRAMS];        /* the slots of a get program hold its present values */
    int prefetch_status[MAX_PROGRAMS];   /* the status of that read */
    int status;            /* reply: worst status of the request */
    int program;           /* request: the program to run; reply: the one that failed */
    long call;             /* reply: the call of the worker's table that failed */
    double t, h;           /* the step's arguments */
    int no_set_prior;
    int op;                /* the request (OP_*) */
    long request_seq;      /* requests posted by the master */
    long reply_seq;        /* requests answered by the worker */
    long seen;             /* the worker's last request taken */
    int worker_sleeping;   /* the worker waits on the request pipe: a request writes a byte there */
    int master_sleeping;   /* the master waits on the reply pipe: a reply writes a byte there */
    Spin worker_spin;
    /* then: double slots[capacity] */
} Shared;

#define SLOTS(s) ((double *)((char *)(s) + (sizeof(Shared) + 7) / 8 * 8))

__attribute__((visibility("default"))) long shared_size(long capacity) {
    return (long)((sizeof(Shared) + 7) / 8 * 8) + 8 * capacity;
}

__attribute__((visibility("default"))) long slots_offset(void) { return (long)((sizeof(Shared) + 7) / 8 * 8); }

__attribute__((visibility("default"))) long shared_failed_call(const Shared *s) { return s->call; }

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
    int program;    /* the program of the request under way, or the one that failed */
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
__attribute__((visibility("default"))) int proxy_request(Proxy *p, int op, int program) {
    Shared *s = p->shared;
    struct pollfd fds[2];
    long deadline, seq;
    if (p->failure) return FMI_FATAL;
    p->program = program;
    s->program = program;
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
    if (FAILED(s->status)) p->program = s->program;
    return s->status;
}

/* One call of the master's runner: a program of the worker, and for a set or get the bus
 * address of each value and its slot in the shared mapping. */
typedef struct {
    Proxy *proxy;
    int program;
    long n;
    const long *slots;
    double *const *where;
} Entry;

/* The runner's vr, n and values arguments are not used: the entry holds them. */
__attribute__((visibility("default"))) int proxy_set(Entry *e, const unsigned int *vr, size_t n, double *values) {
    Proxy *p = e->proxy;
    Shared *s = p->shared;
    double *slots = SLOTS(s);
    long k;
    (void)vr, (void)n, (void)values;
    if (p->failure) return FMI_FATAL;
    for (k = 0; k < e->n; k++) slots[e->slots[k]] = *e->where[k];
    if (!s->pending[e->program]) {
        s->pending[e->program] = 1;
        s->npending++;
    }
    memset(s->prefetched, 0, sizeof s->prefetched); /* an input set may change any output */
    return 0;
}

__attribute__((visibility("default"))) int proxy_get(Entry *e, const unsigned int *vr, size_t n, double *values) {
    Proxy *p = e->proxy;
    Shared *s = p->shared;
    double *slots = SLOTS(s);
    long k;
    int status;
    (void)vr, (void)n, (void)values;
    if (p->failure) return FMI_FATAL;
    if (s->npending == 0 && s->prefetched[e->program]) {
        status = s->prefetch_status[e->program];
    } else {
        status = proxy_request(p, OP_GET, e->program);
        if (FAILED(status)) return status;
    }
    for (k = 0; k < e->n; k++) *e->where[k] = slots[e->slots[k]];
    return status;
}

__attribute__((visibility("default"))) int proxy_step(Entry *e, double t, double h, int no_set_prior) {
    Proxy *p = e->proxy;
    Shared *s = p->shared;
    if (p->failure) return FMI_FATAL;
    s->t = t;
    s->h = h;
    s->no_set_prior = no_set_prior;
    return proxy_request(p, OP_STEP, e->program);
}

/* ------------------------------------------------------------------ the worker's side */
/* One C call of the hosted instance (an quadcosim.orchestrator.fmi_types.CEntry) in program `program`. */
typedef struct {
    void *function;
    void *component;
    const unsigned int *vr;
    size_t n;
    double *values;
    int kind;
    int program;
} Call;

/* Runs program `program`: its worst status, or the first failed one (s->program, s->call say where). */
static int run_program(Shared *s, const Call *calls, long count, int program) {
    long i;
    int status, worst = 0;
    for (i = 0; i < count; i++) {
        const Call *c = &calls[i];
        if (c->program != program) continue;
        if (c->kind == KIND_STEP)
            status = ((DoStep)c->function)(c->component, s->t, s->h, s->no_set_prior);
        else
            status = ((SetOrGet)c->function)(c->component, c->vr, c->n, c->values);
        if (FAILED(status)) {
            s->program = program;
            s->call = i;
            return status;
        }
        worst = status > worst ? status : worst;
    }
    return worst;
}

static int apply_sets(Shared *s, const Call *calls, long count) {
    int p, status, worst = 0;
    if (s->npending == 0) return 0;
    for (p = 0; p < MAX_PROGRAMS; p++) {
        if (!s->pending[p]) continue;
        s->pending[p] = 0;
        status = run_program(s, calls, count, p);
        if (FAILED(status)) {
            memset(s->pending, 0, sizeof s->pending);
            s->npending = 0;
            return status;
        }
        worst = status > worst ? status : worst;
    }
    s->npending = 0;
    return worst;
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

/* Runs requests on the calls of the table until one only Python does (returns OP_PYTHON) or the
 * master is gone (returns 0). */
__attribute__((visibility("default"))) int serve(Shared *s, int request_fd, int reply_fd, const Call *calls,
                                                 long count) {
    for (;;) {
        int status, got, p, program, op = next_request(s, request_fd);
        if (op == 0 || op == OP_PYTHON) return op;
        program = s->program;
        status = apply_sets(s, calls, count);
        if (!FAILED(status) && op == OP_GET) {
            got = run_program(s, calls, count, program);
            s->wanted[program] = 1;
            s->prefetched[program] = !FAILED(got);
            s->prefetch_status[program] = got;
            status = got > status || FAILED(got) ? got : status;
        } else if (!FAILED(status) && op == OP_STEP) {
            memset(s->prefetched, 0, sizeof s->prefetched);
            status = run_program(s, calls, count, program);
            if (!FAILED(status)) { /* the outputs the master reads next, read now */
                for (p = 0; p < MAX_PROGRAMS; p++) {
                    if (!s->wanted[p]) continue;
                    got = run_program(s, calls, count, p);
                    s->prefetched[p] = !FAILED(got);
                    s->prefetch_status[p] = got;
                }
            }
        }
        s->status = status;
        reply(s, reply_fd);
    }
}
