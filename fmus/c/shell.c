/* The FMI 2.0 Co-Simulation API of the shell, over its state machine (cosimulation.h, shared with
 * the FMI 3.0 API in fmi3.c). No model-specific code lives here; see shell.h for what a model
 * provides. */
#include "cosimulation.h"

#if FMI_VERSION != 2
#error "shell.c is the FMI 2.0 API: an FMI 3.0 build compiles fmi3.c"
#endif

#define MASK_fmi2SetupExperiment IN(MODE_INSTANTIATED)
#define MASK_fmi2EnterInitializationMode IN(MODE_INSTANTIATED)
#define MASK_fmi2ExitInitializationMode IN(MODE_INITIALIZATION)
#define MASK_fmi2Terminate (IN(MODE_STEPPING) | IN(MODE_ERROR))
#define MASK_fmi2GetReal MASK_GET
#define MASK_fmi2GetInteger MASK_GET
#define MASK_fmi2GetBoolean MASK_GET
#define MASK_fmi2SetReal MASK_SET
#define MASK_fmi2SetInteger MASK_SET
#define MASK_fmi2SetBoolean MASK_SET
#define MASK_fmi2DoStep IN(MODE_STEPPING)

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
    m = new_instance(instanceName, loggingOn);
    if (!m) return NULL;
    m->callbacks = functions;
    publish(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free_instance(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2SetupExperiment)) return fmi2Error;
    return setup_experiment(m, "fmi2SetupExperiment", toleranceDefined, tolerance, startTime, stopTimeDefined,
                            stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2EnterInitializationMode)) return fmi2Error;
    m->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2ExitInitializationMode)) return fmi2Error;
    return exit_initialization(m, "fmi2ExitInitializationMode");
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
    reset(m);
    return fmi2OK;
}

/* ---------------------------------------------------------------- get and set */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2GetReal)) return fmi2Error;
    return get_reals(m, "fmi2GetReal", vr, nvr, 0, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2GetInteger)) return fmi2Error;
    return get_integers(m, "fmi2GetInteger", vr, nvr, 0, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2GetBoolean)) return fmi2Error;
    if (check_refs(m, "fmi2GetBoolean", vr, nvr, 0, N_BOOLEAN, "Boolean") != fmi2OK) return fmi2Error;
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
    if (!ALLOWED(m, fmi2SetReal)) return fmi2Error;
    return set_reals(m, "fmi2SetReal", vr, nvr, 0, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    ModelInstance *m = live(c);
    if (!ALLOWED(m, fmi2SetInteger)) return fmi2Error;
    return set_integers(m, "fmi2SetInteger", vr, nvr, 0, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    ModelInstance *m = live(c);
    size_t i;
    if (!ALLOWED(m, fmi2SetBoolean)) return fmi2Error;
    if (check_boolean_set(m, "fmi2SetBoolean", vr, nvr, 0, value) != fmi2OK) return fmi2Error;
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
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (!ALLOWED(m, fmi2DoStep)) return fmi2Error;
    return do_step(m, "fmi2DoStep", currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    ModelInstance *m = live(c);
    UNUSED(s);
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
