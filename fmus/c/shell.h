/* The FMI 2.0 Co-Simulation shell shared by every quadcosim model.
 *
 * The shell owns the FMI state machine, get/set by value reference, logging and error
 * statuses. A model provides its variable table (generated variables.h) and the four
 * functions declared at the bottom of this file, in a short model.c.
 */
#ifndef SHELL_H
#define SHELL_H

#include <stddef.h>
#include "fmi2Functions.h"

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
    const fmi2CallbackFunctions *callbacks;
    fmi2Boolean logging_on;
    Mode mode;
    double time;
    double *real;
    int *integer;
    fmi2Boolean *boolean;
    int outputs_stale; /* inputs changed since the outputs were last computed */
    void *data;        /* the model's own state, MODEL_DATA_SIZE bytes */
} ModelInstance;

/* Logging from model code: error messages always reach the environment's logger. */
void log_error(ModelInstance *m, const char *format, ...);
void log_warning(ModelInstance *m, const char *format, ...);

/* Fixed-step classical RK4 over a model's state vector, for models that need nothing else. */
typedef void (*Derivatives)(ModelInstance *m, double t, const double *x, double *dx);
void rk4_step(ModelInstance *m, Derivatives f, double t, double h, double *x, int n);

/* What each model implements. */
extern const size_t MODEL_DATA_SIZE;
/* Check parameters, set the initial state and outputs. */
fmi2Status model_initialize(ModelInstance *m);
/* Advance the state from t to t + h with the inputs held. A model whose state can become
 * non-finite reports it here; outputs are refreshed lazily, when next read. */
fmi2Status model_do_step(ModelInstance *m, double t, double h);
/* Outputs from the state and the present inputs (direct feedthrough). */
void model_outputs(ModelInstance *m);

#endif
