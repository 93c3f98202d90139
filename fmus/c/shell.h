/* The FMI Co-Simulation shell shared by every quadcosim model, for FMI 2.0 and 3.0.
 *
 * The shell owns the FMI state machine, get/set by value reference, logging and error
 * statuses. A model provides its variable table (generated variables.h) and the four
 * functions declared at the bottom of this file, in a short model.c. The same sources build
 * both versions: the state machine (cosimulation.h) under the FMI 2.0 API (shell.c) or the FMI
 * 3.0 API (fmi3.c); variables.h of an FMI 3.0 build defines FMI_VERSION as 3.
 */
#ifndef SHELL_H
#define SHELL_H

#include <stddef.h>

#ifndef FMI_VERSION
#define FMI_VERSION 2
#endif

/* What a model returns (the FMI version's own status values), and the name of an FMI function
 * in its messages: FMI_NAME(DoStep) is "fmi2DoStep" or "fmi3DoStep". */
#if FMI_VERSION == 3
#include "fmi3Functions.h"
typedef fmi3Status Status;
#define STATUS_OK fmi3OK
#define STATUS_WARNING fmi3Warning
#define STATUS_ERROR fmi3Error
#define FMI_NAME(function) "fmi3" #function
#else
#include "fmi2Functions.h"
typedef fmi2Status Status;
#define STATUS_OK fmi2OK
#define STATUS_WARNING fmi2Warning
#define STATUS_ERROR fmi2Error
#define FMI_NAME(function) "fmi2" #function
#endif

typedef enum {
    CAUSALITY_PARAMETER,
    CAUSALITY_INPUT,
    CAUSALITY_OUTPUT,
    CAUSALITY_LOCAL
} Causality;

typedef struct {
    const char *name;
    Causality causality;
    double start;
} VariableInfo;

typedef enum {
    MODE_INSTANTIATED,
    MODE_INITIALIZATION,
    MODE_STEPPING,
    MODE_TERMINATED,
    MODE_ERROR
} Mode;

typedef struct ModelInstance {
    const char *instance_name;
#if FMI_VERSION == 3
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message; /* may be NULL: no logging */
#else
    const fmi2CallbackFunctions *callbacks;
#endif
    int logging_on;
    Mode mode;
    double time;
    double *real;
    int *integer;
    int *boolean; /* 0 or 1 */
    int outputs_stale; /* inputs changed since the outputs were last computed */
    int step_failed;   /* set by a shell helper that refused its work in this doStep */
    void *data;        /* the model's own state, MODEL_DATA_SIZE bytes */
    unsigned live;     /* LIVE_MARK from instantiation to fmiNFreeInstance (shell.c) */
    struct ModelInstance *next_free; /* the next freed slot waiting for reuse */
} ModelInstance;

/* Member k of the Real vector `name` of the variable table (VEC_name, LEN_name in variables.h),
 * e.g. REAL_VECTOR(m, omega_r)[k]: the build checks that a vector's rows are consecutive. */
#define REAL_VECTOR(m, name) (&(m)->real[VEC_##name])

/* Logging from model code: error messages always reach the environment's logger. */
void log_error(ModelInstance *m, const char *format, ...);
void log_warning(ModelInstance *m, const char *format, ...);

/* The most sub-steps (or sensor samples) a model may compute in one doStep. A step or
 * parameters that would need more are refused with a message rather than hanging the caller;
 * at the limit a plant model's doStep takes 30 to 100 ms (a 50 s step of MotorMagnetics at its
 * default sub-step, 200 s of the IMU at 1 kHz). */
#define MAX_SUBSTEPS_PER_STEP 200000

/* Sample clocks of the sensor models: t * rate within this many sample periods of an integer k
 * is the instant k (it absorbs the rounding of t * rate, far below any step a caller takes). */
#define SAMPLE_INSTANT_TOLERANCE 1e-6
/* Whether `count` sub-steps or samples (a real number: it may be huge or non-finite) fit in one
 * doStep of h seconds; if not, logs why, naming what (the printf `what` and its arguments, e.g.
 * "sub-steps of %s = %g s") and the `fix`, and returns 0. Nothing is formatted when it fits. */
int work_allowed(ModelInstance *m, double count, double h, const char *fix, const char *what, ...);
/* Number of equal sub-steps of at most max_step (the model's parameter `parameter`) covering a
 * step h, at least 1; or 0, with the reason logged, beyond MAX_SUBSTEPS_PER_STEP. */
int substep_count(ModelInstance *m, double h, double max_step, const char *parameter);

/* Fixed-step classical RK4 over a model's state vector, for models that need nothing else.
 * Its scratch holds the model's N_STATES states (variables.h); a larger n fails the step. */
typedef void (*Derivatives)(ModelInstance *m, double t, const double *x, double *dx);
void rk4_step(ModelInstance *m, Derivatives f, double t, double h, double *x, int n);

/* What each model implements. */
extern const size_t MODEL_DATA_SIZE;
/* Check parameters, set the initial state and outputs. */
Status model_initialize(ModelInstance *m);
/* Advance the state from t to t + h with the inputs held. A model whose state can become
 * non-finite reports it here; outputs are refreshed lazily, when next read. */
Status model_do_step(ModelInstance *m, double t, double h);
/* Outputs from the state and the present inputs (direct feedthrough). */
void model_outputs(ModelInstance *m);

#endif
