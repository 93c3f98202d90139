/* A model's equations stepped without the FMI shell: model_do_step and model_outputs called
 * directly, with the signature of fmi2DoStep, so that the benchmark times the same step through
 * the FMU and without it. Compiled with the FMU's own staged sources (shell.c, model.c) and
 * flags into one library per model; not part of any FMU. */
#include "shell.h"

FMI2_Export fmi2Status equations_step(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean unused) {
    ModelInstance *m = (ModelInstance *)c;
    fmi2Status status;
    (void)unused;
    status = model_do_step(m, t, h);
    m->time = t + h;
    model_outputs(m);
    m->outputs_stale = 0;
    return status;
}
