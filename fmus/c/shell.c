/* FMI 2.0 Co-Simulation shell: state machine, get/set by value reference, logging, status.
 * No model-specific code lives here; see shell.h for what a model provides. */
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
 * the slots, and every call on it answers fmi2Error instead of touching freed memory (FMI 2.0
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
static ModelInstance *live(fmi2Component c) {
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

static void vlog(ModelInstance *m, fmi2Status status, const char *category, const char *format,
                 va_list args) {
    char message[LOG_MESSAGE_SIZE];
    if (!m || !m->callbacks || !m->callbacks->logger) return;
    if (status == fmi2OK && !m->logging_on) return;
    vsnprintf(message, sizeof message, format, args);
    m->callbacks->logger(m->callbacks->componentEnvironment, m->instance_name, status, category,
                         "%s", message);
}

void log_error(ModelInstance *m, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(m, fmi2Error, "logStatusError", format, args);
    va_end(args);
}

void log_warning(ModelInstance *m, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(m, fmi2Warning, "logStatusWarning", format, args);
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
    log_error(m, "fmi2DoStep: a step of %g s at t = %g would need %.3g %s, more than the %d allowed "
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

static fmi2Status fail(ModelInstance *m, const char *function, const char *format, ...) {
    char message[FAIL_MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    log_error(m, "%s: %s", function, message);
    return fmi2Error;
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

/* The modes in which each FMI function may be called (FMI 2.0, section 4.2.4), as bit masks
 * named after the function; ALLOWED(m, f) checks f's mask and names the modes in its message. */
#define IN(mode) (1u << (mode))
#define MASK_fmi2SetupExperiment IN(MODE_INSTANTIATED)
#define MASK_fmi2EnterInitializationMode IN(MODE_INSTANTIATED)
#define MASK_fmi2ExitInitializationMode IN(MODE_INITIALIZATION)
#define MASK_fmi2Terminate (IN(MODE_STEPPING) | IN(MODE_ERROR))
#define MASK_GET (IN(MODE_INSTANTIATED) | IN(MODE_INITIALIZATION) | IN(MODE_STEPPING) | IN(MODE_TERMINATED))
#define MASK_fmi2GetReal MASK_GET
#define MASK_fmi2GetInteger MASK_GET
#define MASK_fmi2GetBoolean MASK_GET
#define MASK_SET (IN(MODE_INSTANTIATED) | IN(MODE_INITIALIZATION) | IN(MODE_STEPPING))
#define MASK_fmi2SetReal MASK_SET
#define MASK_fmi2SetInteger MASK_SET
#define MASK_fmi2SetBoolean MASK_SET
#define MASK_fmi2DoStep IN(MODE_STEPPING)
#define ALLOWED(m, function) allowed((m), #function, MASK_##function)

/* The Real variables a step can change: outputs and locals. Parameters and inputs are checked
 * when set (fmi2SetReal refuses a non-finite value) and their start values are finite. Filled
 * by the first fmi2Instantiate, under the slot lock, before any instance can step. */
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

/* ---------------------------------------------------------------- common functions */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    ModelInstance *m = live(c);
    UNUSED(nCategories);
    UNUSED(categories);
    if (!m) return fmi2Error;
    m->logging_on = loggingOn;
    return fmi2OK;
}

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

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    ModelInstance *m;
    UNUSED(fmuResourceLocation);
    UNUSED(visible);
    if (!functions || !functions->logger) return NULL;
    if (!instanceName || !*instanceName) instanceName = MODEL_NAME;
    if (fmuType != fmi2CoSimulation) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                          "fmi2Instantiate: %s supports Co-Simulation only", MODEL_NAME);
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, MODEL_GUID) != 0) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                          "fmi2Instantiate: GUID %s does not match %s; rebuild the FMU",
                          fmuGUID ? fmuGUID : "(null)", MODEL_GUID);
        return NULL;
    }
    m = take_slot();
    if (!m) return NULL;
    m->instance_name = (char *)malloc(strlen(instanceName) + 1);
    if (m->instance_name) strcpy((char *)m->instance_name, instanceName);
    m->callbacks = functions;
    m->logging_on = loggingOn;
    m->real = (double *)calloc(N_REAL > 0 ? N_REAL : 1, sizeof(double));
    m->integer = (int *)calloc(N_INTEGER > 0 ? N_INTEGER : 1, sizeof(int));
    m->boolean = (fmi2Boolean *)calloc(N_BOOLEAN > 0 ? N_BOOLEAN : 1, sizeof(fmi2Boolean));
    m->data = calloc(1, MODEL_DATA_SIZE > 0 ? MODEL_DATA_SIZE : 1);
    if (!m->instance_name || !m->real || !m->integer || !m->boolean || !m->data) {
        release(m);
        return NULL;
    }
    reset_values(m);
    m->mode = MODE_INSTANTIATED;
    __atomic_store_n(&m->live, LIVE_MARK, __ATOMIC_RELEASE);
    return m;
}

/* A freed handle, freed again or never issued, is ignored: fmi2FreeInstance returns no status. */
void fmi2FreeInstance(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!m) return;
    __atomic_store_n(&m->live, 0u, __ATOMIC_RELEASE);
    release(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2SetupExperiment)) return fmi2Error;
    if (!isfinite(startTime))
        return fail(m, "fmi2SetupExperiment", "startTime = %g is not a finite number", startTime);
    if (toleranceDefined && !(tolerance > 0.0 && isfinite(tolerance)))
        return fail(m, "fmi2SetupExperiment", "tolerance = %g must be positive and finite", tolerance);
    if (stopTimeDefined && !(stopTime >= startTime && isfinite(stopTime)))
        return fail(m, "fmi2SetupExperiment", "stopTime = %g must be finite and not before startTime = %g",
                    stopTime, startTime);
    m->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2EnterInitializationMode)) return fmi2Error;
    m->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    ModelInstance *m = live(c);
    fmi2Status status;
    int bad;
    if (!ALLOWED(m, fmi2ExitInitializationMode)) return fmi2Error;
    status = model_initialize(m);
    if (status > fmi2Warning) {
        m->mode = MODE_ERROR;
        return status;
    }
    model_outputs(m);
    m->outputs_stale = 0;
    bad = first_non_finite(m);
    if (bad >= 0) {
        m->mode = MODE_ERROR;
        return fail(m, "fmi2ExitInitializationMode", "%s is not finite after initialization",
                    REAL_INFO[bad].name);
    }
    m->mode = MODE_STEPPING;
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2Terminate)) return fmi2Error;
    m->mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!m) return fmi2Error;
    reset_values(m);
    m->mode = MODE_INSTANTIATED;
    return fmi2OK;
}

/* ---------------------------------------------------------------- get and set */
static fmi2Status check_refs(ModelInstance *m, const char *function, const fmi2ValueReference vr[],
                             size_t nvr, int count, const char *type) {
    size_t i;
    if (nvr > 0 && !vr) return fail(m, function, "null value reference array");
    for (i = 0; i < nvr; i++) { /* unsigned: a reference of 2^31 or more is not a negative index */
        if (vr[i] >= (fmi2ValueReference)count)
            return fail(m, function, "unknown value reference %u: this model has %d %s variables, 0 to %d",
                        (unsigned)vr[i], count, type, count - 1);
    }
    return fmi2OK;
}

static fmi2Status check_settable(ModelInstance *m, const char *function, const VariableInfo *info) {
    if (info->causality == CAUSALITY_PARAMETER && m->mode != MODE_INSTANTIATED &&
        m->mode != MODE_INITIALIZATION)
        return fail(m, function, "parameter %s can only be set before initialization ends",
                    info->name);
    if (info->causality == CAUSALITY_OUTPUT || info->causality == CAUSALITY_LOCAL)
        return fail(m, function, "%s is an output and cannot be set", info->name);
    return fmi2OK;
}

/* Outputs are computed when read, once per change of state or inputs. */
static fmi2Status refresh_outputs(ModelInstance *m, const char *function) {
    int bad;
    if (!m->outputs_stale || m->mode != MODE_STEPPING) return fmi2OK;
    model_outputs(m);
    m->outputs_stale = 0;
    bad = first_non_finite(m);
    if (bad >= 0) {
        m->mode = MODE_ERROR;
        return fail(m, function, "%s became %g at t = %g", REAL_INFO[bad].name, m->real[bad], m->time);
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2GetReal)) return fmi2Error;
    if (check_refs(m, "fmi2GetReal", vr, nvr, N_REAL, "Real") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2GetReal", "null value array");
    if (refresh_outputs(m, "fmi2GetReal") != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) value[i] = m->real[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2GetInteger)) return fmi2Error;
    if (check_refs(m, "fmi2GetInteger", vr, nvr, N_INTEGER, "Integer") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2GetInteger", "null value array");
    for (i = 0; i < nvr; i++) value[i] = m->integer[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2GetBoolean)) return fmi2Error;
    if (check_refs(m, "fmi2GetBoolean", vr, nvr, N_BOOLEAN, "Boolean") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2GetBoolean", "null value array");
    for (i = 0; i < nvr; i++) value[i] = m->boolean[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    ModelInstance *m = live(c);
    UNUSED(vr);
    UNUSED(value);
    if (!m) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(m, "fmi2GetString", "this model has no String variables");
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2SetReal)) return fmi2Error;
    if (check_refs(m, "fmi2SetReal", vr, nvr, N_REAL, "Real") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2SetReal", "null value array");
    for (i = 0; i < nvr; i++) {
        const VariableInfo *info = &REAL_INFO[vr[i]];
        if (check_settable(m, "fmi2SetReal", info) != fmi2OK) return fmi2Error;
        if (!isfinite(value[i])) {
            m->mode = MODE_ERROR;
            return fail(m, "fmi2SetReal", "%s = %g at t = %g is not a finite number", info->name,
                        value[i], m->time);
        }
    }
    for (i = 0; i < nvr; i++) m->real[vr[i]] = value[i];
    m->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2SetInteger)) return fmi2Error;
    if (check_refs(m, "fmi2SetInteger", vr, nvr, N_INTEGER, "Integer") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2SetInteger", "null value array");
    for (i = 0; i < nvr; i++)
        if (check_settable(m, "fmi2SetInteger", &INTEGER_INFO[vr[i]]) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) m->integer[vr[i]] = value[i];
    m->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2SetBoolean)) return fmi2Error;
    if (check_refs(m, "fmi2SetBoolean", vr, nvr, N_BOOLEAN, "Boolean") != fmi2OK) return fmi2Error;
    if (nvr > 0 && !value) return fail(m, "fmi2SetBoolean", "null value array");
    for (i = 0; i < nvr; i++)
        if (check_settable(m, "fmi2SetBoolean", &BOOLEAN_INFO[vr[i]]) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) m->boolean[vr[i]] = value[i] ? fmi2True : fmi2False;
    m->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    ModelInstance *m = live(c);
    UNUSED(vr);
    UNUSED(value);
    if (!m) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    return fail(m, "fmi2SetString", "this model has no String variables");
}

/* ---------------------------------------------------------------- unsupported capabilities */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    UNUSED(s);
    return fail(live(c), "fmi2GetFMUstate", "not supported");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    UNUSED(s);
    return fail(live(c), "fmi2SetFMUstate", "not supported");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    UNUSED(s);
    return fail(live(c), "fmi2FreeFMUstate", "not supported");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    UNUSED(s);
    UNUSED(size);
    return fail(live(c), "fmi2SerializedFMUstateSize", "not supported");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[], size_t size) {
    UNUSED(s);
    UNUSED(bytes);
    UNUSED(size);
    return fail(live(c), "fmi2SerializeFMUstate", "not supported");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *s) {
    UNUSED(bytes);
    UNUSED(size);
    UNUSED(s);
    return fail(live(c), "fmi2DeSerializeFMUstate", "not supported");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    UNUSED(u);
    UNUSED(nu);
    UNUSED(z);
    UNUSED(nz);
    UNUSED(dv);
    UNUSED(dz);
    return fail(live(c), "fmi2GetDirectionalDerivative", "not supported");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    UNUSED(vr);
    UNUSED(nvr);
    UNUSED(order);
    UNUSED(value);
    return fail(live(c), "fmi2SetRealInputDerivatives", "not supported");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    UNUSED(vr);
    UNUSED(nvr);
    UNUSED(order);
    UNUSED(value);
    return fail(live(c), "fmi2GetRealOutputDerivatives", "not supported");
}
fmi2Status fmi2CancelStep(fmi2Component c) {
    return fail(live(c), "fmi2CancelStep", "doStep is synchronous; nothing to cancel");
}

/* ---------------------------------------------------------------- stepping */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    ModelInstance *m = live(c);
    double t = currentCommunicationPoint, h = communicationStepSize;
    fmi2Status status;
    int bad;
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (!ALLOWED(m, fmi2DoStep)) return fmi2Error;
    if (!(h > 0.0) || !isfinite(h))
        return fail(m, "fmi2DoStep", "step size %g must be positive and finite", h);
    if (!isfinite(t) || !isfinite(t + h))
        return fail(m, "fmi2DoStep", "communication point %g (step %g) is not a finite time", t, h);
    if (!(fabs(t - m->time) <= TIME_MATCH_TOLERANCE * (1.0 + fabs(m->time))))
        return fail(m, "fmi2DoStep", "communication point %.12g differs from the model time %.12g", t,
                    m->time);
    m->step_failed = 0;
    status = model_do_step(m, t, h);
    if (m->step_failed && status < fmi2Error) status = fmi2Error;
    if (status > fmi2Warning) { /* the time stays at the last successful communication point */
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
        return fail(m, "fmi2DoStep", "%s became %g in the step from t = %g to %g", REAL_INFO[bad].name,
                    m->real[bad], t, t + h);
    }
    return status;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    UNUSED(s);
    ModelInstance *m = live(c);
    if (!m || !value) return fmi2Error;
    *value = m->mode == MODE_ERROR ? fmi2Error : fmi2OK;
    return fmi2OK;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    ModelInstance *m = live(c);
    if (!m || !value) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = m->time;
        return fmi2OK;
    }
    return fail(m, "fmi2GetRealStatus", "status kind %d not supported", (int)s);
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    UNUSED(s);
    UNUSED(value);
    return fail(live(c), "fmi2GetIntegerStatus", "not supported");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    ModelInstance *m = live(c);
    if (!m || !value) return fmi2Error;
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fail(m, "fmi2GetBooleanStatus", "status kind %d not supported", (int)s);
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    UNUSED(s);
    UNUSED(value);
    return fail(live(c), "fmi2GetStringStatus", "not supported");
}
