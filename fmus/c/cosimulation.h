/* The Co-Simulation state machine of the shell, for both FMI versions: live instances, logging,
 * the helpers a model calls (shell.h), the checks, get and set by value reference, and the step.
 * Included by exactly one API file per build: shell.c (FMI 2.0) or fmi3.c (FMI 3.0). */
#ifndef COSIMULATION_H
#define COSIMULATION_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "variables.h"

#define UNUSED(x) (void)(x)

/* Room for one log message and for the pieces it is assembled from (characters). */
#define LOG_MESSAGE_SIZE 1024
#define FAIL_MESSAGE_SIZE 900
#define SHORT_TEXT_SIZE 128

/* A communication point matches the model time within this relative tolerance: a master that
 * computes t = n * dt accumulates rounding, never a real gap. */
#define TIME_MATCH_TOLERANCE 1e-9
/* h / max_step that exceeds an integer by no more than this is rounding: no extra sub-step. */
#define SUBSTEP_ROUNDING 1e-9

/* RK4 scratch: one vector per stage, sized by the model's state count. */
#define RK4_CAPACITY (N_STATES > 0 ? N_STATES : 1)

/* ---------------------------------------------------------------- live instances
 * Instances live in slots that are never returned to the system. A handle that was freed, or
 * never issued, therefore points either at a slot whose mark says it is not live or at none of
 * the slots, and every call on it answers an error instead of touching freed memory (FMI
 * leaves such calls undefined). A freed slot is reused only after SLOT_QUARANTINE later frees,
 * so that a stale handle keeps failing for that long. Slots are taken and given back under a
 * spin lock (instantiation is rare); the check itself reads only published memory. */
#define SLOTS_PER_CHUNK 64
#define SLOT_QUARANTINE 256
#define LIVE_MARK 0x51C051D5u

typedef struct Chunk {
    ModelInstance slot[SLOTS_PER_CHUNK];
    struct Chunk *next;
} Chunk;

static Chunk *chunks;                      /* newest first; a chunk is published whole */
static int chunks_used;                    /* slots handed out from the newest chunk */
static ModelInstance *freed_head, *freed_tail; /* freed slots, oldest first */
static int freed_count;
static char slot_lock;

static void lock_slots(void) {
    while (__atomic_test_and_set(&slot_lock, __ATOMIC_ACQUIRE)) {
    }
}

static void unlock_slots(void) { __atomic_clear(&slot_lock, __ATOMIC_RELEASE); }

static void index_checked(void);

/* A zeroed slot: a quarantined one when enough have waited, else a new one; NULL when out of memory. */
static ModelInstance *take_slot(void) {
    ModelInstance *m = NULL;
    lock_slots();
    index_checked();
    if (freed_count > SLOT_QUARANTINE) {
        m = freed_head;
        freed_head = m->next_free;
        if (!freed_head) freed_tail = NULL;
        freed_count--;
    } else {
        if (!chunks || chunks_used == SLOTS_PER_CHUNK) {
            Chunk *chunk = (Chunk *)calloc(1, sizeof(Chunk));
            if (chunk) {
                chunk->next = chunks;
                __atomic_store_n(&chunks, chunk, __ATOMIC_RELEASE);
                chunks_used = 0;
            }
        }
        if (chunks && chunks_used < SLOTS_PER_CHUNK) m = &chunks->slot[chunks_used++];
    }
    unlock_slots();
    if (m) memset(m, 0, sizeof *m);
    return m;
}

static void give_slot(ModelInstance *m) {
    lock_slots();
    m->next_free = NULL;
    if (freed_tail) freed_tail->next_free = m;
    else freed_head = m;
    freed_tail = m;
    freed_count++;
    unlock_slots();
}

/* The instance behind handle c if it is live, else NULL. */
static ModelInstance *live(void *c) {
    const Chunk *chunk;
    uintptr_t p = (uintptr_t)c;
    for (chunk = __atomic_load_n(&chunks, __ATOMIC_ACQUIRE); chunk; chunk = chunk->next) {
        uintptr_t base = (uintptr_t)chunk->slot;
        if (p < base || p >= base + sizeof chunk->slot) continue;
        if ((p - base) % sizeof(ModelInstance)) return NULL;
        return __atomic_load_n(&((ModelInstance *)c)->live, __ATOMIC_ACQUIRE) == LIVE_MARK ? (ModelInstance *)c
                                                                                           : NULL;
    }
    return NULL;
}

static void vlog(ModelInstance *m, Status status, const char *category, const char *format, va_list args) {
    char message[LOG_MESSAGE_SIZE];
#if FMI_VERSION == 3
    if (!m || !m->log_message) return;
#else
    if (!m || !m->callbacks || !m->callbacks->logger) return;
#endif
    if (status == STATUS_OK && !m->logging_on) return;
    vsnprintf(message, sizeof message, format, args);
#if FMI_VERSION == 3
    m->log_message(m->environment, status, category, message);
#else
    m->callbacks->logger(m->callbacks->componentEnvironment, m->instance_name, status, category,
                         "%s", message);
#endif
}

void log_error(ModelInstance *m, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(m, STATUS_ERROR, "logStatusError", format, args);
    va_end(args);
}

void log_warning(ModelInstance *m, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(m, STATUS_WARNING, "logStatusWarning", format, args);
    va_end(args);
}

void rk4_step(ModelInstance *m, Derivatives f, double t, double h, double *x, int n) {
    double k1[RK4_CAPACITY], k2[RK4_CAPACITY], k3[RK4_CAPACITY], k4[RK4_CAPACITY], tmp[RK4_CAPACITY];
    int i;
    if (n < 0 || n > N_STATES) {
        log_error(m, "rk4_step: %d states, but the variable table declares %d (states=...)", n, N_STATES);
        m->step_failed = 1;
        return;
    }
    f(m, t, x, k1);
    for (i = 0; i < n; i++) tmp[i] = x[i] + 0.5 * h * k1[i];
    f(m, t + 0.5 * h, tmp, k2);
    for (i = 0; i < n; i++) tmp[i] = x[i] + 0.5 * h * k2[i];
    f(m, t + 0.5 * h, tmp, k3);
    for (i = 0; i < n; i++) tmp[i] = x[i] + h * k3[i];
    f(m, t + h, tmp, k4);
    for (i = 0; i < n; i++) x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

int work_allowed(ModelInstance *m, double count, double h, const char *fix, const char *what, ...) {
    char text[SHORT_TEXT_SIZE];
    va_list args;
    if (count <= (double)MAX_SUBSTEPS_PER_STEP) return 1; /* false for NaN */
    /* the description is formatted only here, on the refusal: a step that fits does no I/O */
    va_start(args, what);
    vsnprintf(text, sizeof text, what, args);
    va_end(args);
    log_error(m, FMI_NAME(DoStep) ": a step of %g s at t = %g would need %.3g %s, more than the %d allowed "
                 "per step; %s",
              h, m->time, count, text, MAX_SUBSTEPS_PER_STEP, fix);
    return 0;
}

int substep_count(ModelInstance *m, double h, double max_step, const char *parameter) {
    double count = ceil(h / max_step - SUBSTEP_ROUNDING);
    if (count < 1.0) return 1;
    if (!work_allowed(m, count, h, "take shorter communication steps or a larger sub-step",
                      "sub-steps of %s = %g s", parameter, max_step))
        return 0;
    return (int)count;
}

static Status fail(ModelInstance *m, const char *function, const char *format, ...) {
    char message[FAIL_MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    log_error(m, "%s: %s", function, message);
    return STATUS_ERROR;
}

static const char *const MODE_NAMES[] = {"instantiated", "in initialization mode", "in step mode",
                                         "terminated", "in the error state"};

static int allowed(ModelInstance *m, const char *function, unsigned modes) {
    char list[SHORT_TEXT_SIZE] = "";
    int k;
    if (!m) return 0;
    if ((1u << m->mode) & modes) return 1;
    for (k = 0; k <= MODE_ERROR; k++) {
        if (!((1u << k) & modes)) continue;
        if (*list) strcat(list, ", ");
        strcat(list, MODE_NAMES[k]);
    }
    fail(m, function, "not allowed: the FMU is %s (allowed only when it is %s)", MODE_NAMES[m->mode],
         list);
    return 0;
}

/* The modes in which each FMI function may be called (FMI 2.0, section 4.2.4; FMI 3.0, section
 * 4.2.1), as bit masks named after the function (MASK_fmi2DoStep, MASK_fmi3DoStep, beside each
 * version's API); ALLOWED(m, f) checks f's mask and names the modes in its message. */
#define IN(mode) (1u << (mode))
#define MASK_GET (IN(MODE_INSTANTIATED) | IN(MODE_INITIALIZATION) | IN(MODE_STEPPING) | IN(MODE_TERMINATED))
#define MASK_SET (IN(MODE_INSTANTIATED) | IN(MODE_INITIALIZATION) | IN(MODE_STEPPING))
#define ALLOWED(m, function) allowed((m), #function, MASK_##function)

/* The Real variables a step can change: outputs and locals. Parameters and inputs are checked
 * when set (a non-finite value is refused) and their start values are finite. Filled by the
 * first instantiation, under the slot lock, before any instance can step. */
static int checked_index[N_REAL > 0 ? N_REAL : 1];
static int checked_count = -1;

static void index_checked(void) {
    int i;
    if (checked_count >= 0) return;
    checked_count = 0;
    for (i = 0; i < N_REAL; i++)
        if (REAL_INFO[i].causality == CAUSALITY_OUTPUT || REAL_INFO[i].causality == CAUSALITY_LOCAL)
            checked_index[checked_count++] = i;
}

/* Index of the first non-finite output or local, or -1. x * 0 is 0 for a finite x and NaN
 * otherwise, so the sum tells without a branch per variable; the search runs only on a NaN. */
static int first_non_finite(ModelInstance *m) {
    double probe = 0.0;
    int k;
    for (k = 0; k < checked_count; k++) probe += m->real[checked_index[k]] * 0.0;
    if (probe == 0.0) return -1;
    for (k = 0; k < checked_count; k++)
        if (!isfinite(m->real[checked_index[k]])) return checked_index[k];
    return -1;
}

static void reset_values(ModelInstance *m) {
    int i;
    for (i = 0; i < N_REAL; i++) m->real[i] = REAL_INFO[i].start;
    for (i = 0; i < N_INTEGER; i++) m->integer[i] = (int)INTEGER_INFO[i].start;
    for (i = 0; i < N_BOOLEAN; i++) m->boolean[i] = BOOLEAN_INFO[i].start != 0.0;
    memset(m->data, 0, MODEL_DATA_SIZE);
    m->time = 0.0;
    m->outputs_stale = 1;
}

/* ---------------------------------------------------------------- the state machine, for both APIs */
static void release(ModelInstance *m) {
    free((void *)m->instance_name);
    free(m->real);
    free(m->integer);
    free(m->boolean);
    free(m->data);
    m->instance_name = NULL;
    m->real = NULL;
    m->integer = NULL;
    m->boolean = NULL;
    m->data = NULL;
    give_slot(m);
}

/* A new instance at its start values, not yet live (the API sets its logger, then publishes
 * it), or NULL when out of memory. */
static ModelInstance *new_instance(const char *instance_name, int logging_on) {
    ModelInstance *m = take_slot();
    if (!m) return NULL;
    m->instance_name = (char *)malloc(strlen(instance_name) + 1);
    if (m->instance_name) strcpy((char *)m->instance_name, instance_name);
    m->logging_on = logging_on;
    m->real = (double *)calloc(N_REAL > 0 ? N_REAL : 1, sizeof(double));
    m->integer = (int *)calloc(N_INTEGER > 0 ? N_INTEGER : 1, sizeof(int));
    m->boolean = (int *)calloc(N_BOOLEAN > 0 ? N_BOOLEAN : 1, sizeof(int));
    m->data = calloc(1, MODEL_DATA_SIZE > 0 ? MODEL_DATA_SIZE : 1);
    if (!m->instance_name || !m->real || !m->integer || !m->boolean || !m->data) {
        release(m);
        return NULL;
    }
    reset_values(m);
    m->mode = MODE_INSTANTIATED;
    return m;
}

static void publish(ModelInstance *m) { __atomic_store_n(&m->live, LIVE_MARK, __ATOMIC_RELEASE); }

/* A freed handle, freed again or never issued, is ignored: fmiNFreeInstance returns no status. */
static void free_instance(void *c) {
    ModelInstance *m = live(c);
    if (!m) return;
    __atomic_store_n(&m->live, 0u, __ATOMIC_RELEASE);
    release(m);
}

static Status setup_experiment(ModelInstance *m, const char *function, int toleranceDefined, double tolerance,
                               double startTime, int stopTimeDefined, double stopTime) {
    if (!isfinite(startTime)) return fail(m, function, "startTime = %g is not a finite number", startTime);
    if (toleranceDefined && !(tolerance > 0.0 && isfinite(tolerance)))
        return fail(m, function, "tolerance = %g must be positive and finite", tolerance);
    if (stopTimeDefined && !(stopTime >= startTime && isfinite(stopTime)))
        return fail(m, function, "stopTime = %g must be finite and not before startTime = %g", stopTime,
                    startTime);
    m->time = startTime;
    return STATUS_OK;
}

static Status exit_initialization(ModelInstance *m, const char *function) {
    Status status = model_initialize(m);
    int bad;
    if (status > STATUS_WARNING) {
        m->mode = MODE_ERROR;
        return status;
    }
    model_outputs(m);
    m->outputs_stale = 0;
    bad = first_non_finite(m);
    if (bad >= 0) {
        m->mode = MODE_ERROR;
        return fail(m, function, "%s is not finite after initialization", REAL_INFO[bad].name);
    }
    m->mode = MODE_STEPPING;
    return status;
}

static void reset(ModelInstance *m) {
    reset_values(m);
    m->mode = MODE_INSTANTIATED;
}

/* Value references vr[0..nvr) of variables of one type, numbered from `first` (FMI 2.0 numbers
 * each type from 0; FMI 3.0 numbers all variables in one sequence), `count` of them. */
static Status check_refs(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                         unsigned int first, int count, const char *type) {
    size_t i;
    if (nvr > 0 && !vr) return fail(m, function, "null value reference array");
    for (i = 0; i < nvr; i++) { /* unsigned: a reference below `first` wraps beyond count */
        if (vr[i] - first >= (unsigned int)count)
            return fail(m, function, "unknown value reference %u: this model has %d %s variables, %u to %d",
                        (unsigned)vr[i], count, type, first, (int)first + count - 1);
    }
    return STATUS_OK;
}

static Status check_settable(ModelInstance *m, const char *function, const VariableInfo *info) {
    if (info->causality == CAUSALITY_PARAMETER && m->mode != MODE_INSTANTIATED &&
        m->mode != MODE_INITIALIZATION)
        return fail(m, function, "parameter %s can only be set before initialization ends", info->name);
    if (info->causality == CAUSALITY_OUTPUT || info->causality == CAUSALITY_LOCAL)
        return fail(m, function, "%s is an output and cannot be set", info->name);
    return STATUS_OK;
}

/* Outputs are computed when read, once per change of state or inputs. */
static Status refresh_outputs(ModelInstance *m, const char *function) {
    int bad;
    if (!m->outputs_stale || m->mode != MODE_STEPPING) return STATUS_OK;
    model_outputs(m);
    m->outputs_stale = 0;
    bad = first_non_finite(m);
    if (bad >= 0) {
        m->mode = MODE_ERROR;
        return fail(m, function, "%s became %g at t = %g", REAL_INFO[bad].name, m->real[bad], m->time);
    }
    return STATUS_OK;
}

/* The Real (FMI 3.0: Float64) and Integer (Int32) get and set, after the mode check; a Boolean's
 * FMI type differs between the versions, so each API copies its own. */
static Status get_reals(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                        unsigned int first, double value[]) {
    size_t i;
    if (check_refs(m, function, vr, nvr, first, N_REAL, "Real") != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0 && !value) return fail(m, function, "null value array");
    if (refresh_outputs(m, function) != STATUS_OK) return STATUS_ERROR;
    for (i = 0; i < nvr; i++) value[i] = m->real[vr[i] - first];
    return STATUS_OK;
}

static Status get_integers(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                           unsigned int first, int value[]) {
    size_t i;
    if (check_refs(m, function, vr, nvr, first, N_INTEGER, "Integer") != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0 && !value) return fail(m, function, "null value array");
    for (i = 0; i < nvr; i++) value[i] = m->integer[vr[i] - first];
    return STATUS_OK;
}

static Status set_reals(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                        unsigned int first, const double value[]) {
    size_t i;
    if (check_refs(m, function, vr, nvr, first, N_REAL, "Real") != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0 && !value) return fail(m, function, "null value array");
    for (i = 0; i < nvr; i++) {
        const VariableInfo *info = &REAL_INFO[vr[i] - first];
        if (check_settable(m, function, info) != STATUS_OK) return STATUS_ERROR;
        if (!isfinite(value[i])) {
            m->mode = MODE_ERROR;
            return fail(m, function, "%s = %g at t = %g is not a finite number", info->name, value[i], m->time);
        }
    }
    for (i = 0; i < nvr; i++) m->real[vr[i] - first] = value[i];
    m->outputs_stale = 1;
    return STATUS_OK;
}

static Status set_integers(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                           unsigned int first, const int value[]) {
    size_t i;
    if (check_refs(m, function, vr, nvr, first, N_INTEGER, "Integer") != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0 && !value) return fail(m, function, "null value array");
    for (i = 0; i < nvr; i++)
        if (check_settable(m, function, &INTEGER_INFO[vr[i] - first]) != STATUS_OK) return STATUS_ERROR;
    for (i = 0; i < nvr; i++) m->integer[vr[i] - first] = value[i];
    m->outputs_stale = 1;
    return STATUS_OK;
}

/* Booleans are checked here and copied by each API (their FMI types differ). */
static Status check_boolean_set(ModelInstance *m, const char *function, const unsigned int vr[], size_t nvr,
                                unsigned int first, const void *value) {
    size_t i;
    if (check_refs(m, function, vr, nvr, first, N_BOOLEAN, "Boolean") != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0 && !value) return fail(m, function, "null value array");
    for (i = 0; i < nvr; i++)
        if (check_settable(m, function, &BOOLEAN_INFO[vr[i] - first]) != STATUS_OK) return STATUS_ERROR;
    return STATUS_OK;
}

static Status do_step(ModelInstance *m, const char *function, double t, double h) {
    Status status;
    int bad;
    if (!(h > 0.0) || !isfinite(h)) return fail(m, function, "step size %g must be positive and finite", h);
    if (!isfinite(t) || !isfinite(t + h))
        return fail(m, function, "communication point %g (step %g) is not a finite time", t, h);
    if (!(fabs(t - m->time) <= TIME_MATCH_TOLERANCE * (1.0 + fabs(m->time))))
        return fail(m, function, "communication point %.12g differs from the model time %.12g", t, m->time);
    m->step_failed = 0;
    status = model_do_step(m, t, h);
    if (m->step_failed && status < STATUS_ERROR) status = STATUS_ERROR;
    if (status > STATUS_WARNING) { /* the time stays at the last successful communication point */
        m->mode = MODE_ERROR;
        return status;
    }
    m->time = t + h; /* the outputs are those at t + h */
    /* outputs (which include the state) are checked here, so that a state that became
     * non-finite fails this step rather than the next read */
    model_outputs(m);
    m->outputs_stale = 0;
    bad = first_non_finite(m);
    if (bad >= 0) {
        m->time = t;
        m->mode = MODE_ERROR;
        return fail(m, function, "%s became %g in the step from t = %g to %g", REAL_INFO[bad].name, m->real[bad],
                    t, t + h);
    }
    return status;
}

#endif
