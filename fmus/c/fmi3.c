/* The FMI 3.0 Co-Simulation API of the shell, over the state machine it shares with the FMI 2.0
 * API (cosimulation.h). The model's Real, Integer and Boolean variables are Float64, Int32 and
 * Boolean here. FMI 3.0 numbers all variables in one sequence: 0 is the independent variable
 * time, then the Real variables in table order, the Integer ones and the Boolean ones, so that
 * value reference vr of a type is index vr - FIRST_<type> of the instance's array of that type
 * (the build writes the same numbers into modelDescription.xml). A Real vector the variable
 * table names an array (IMU.acc) is one Float64 variable of several values, at the reference of
 * its first element. */
#include "cosimulation.h"

#if FMI_VERSION != 3
#error "fmi3.c is the FMI 3.0 API: variables.h of an FMI 3.0 build defines FMI_VERSION 3"
#endif

#define VR_TIME 0u
#define FIRST_REAL 1u
#define FIRST_INTEGER (FIRST_REAL + N_REAL)
#define FIRST_BOOLEAN (FIRST_INTEGER + N_INTEGER)

#define MASK_fmi3EnterInitializationMode IN(MODE_INSTANTIATED)
#define MASK_fmi3ExitInitializationMode IN(MODE_INITIALIZATION)
#define MASK_fmi3Terminate (IN(MODE_STEPPING) | IN(MODE_ERROR))
#define MASK_fmi3GetFloat64 MASK_GET
#define MASK_fmi3GetInt32 MASK_GET
#define MASK_fmi3GetBoolean MASK_GET
#define MASK_fmi3SetFloat64 MASK_SET
#define MASK_fmi3SetInt32 MASK_SET
#define MASK_fmi3SetBoolean MASK_SET
#define MASK_fmi3DoStep IN(MODE_STEPPING)

/* Every variable is a scalar: one value per value reference. */
static Status check_scalars(ModelInstance *m, const char *function, size_t nvr, size_t nValues) {
    if (nValues == nvr) return fmi3OK;
    return fail(m, function, "%lu values for %lu value references: every variable of %s is a scalar",
                (unsigned long)nValues, (unsigned long)nvr, MODEL_NAME);
}

/* ---------------------------------------------------------------- common functions */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    ModelInstance *m = live(instance);
    UNUSED(nCategories);
    UNUSED(categories);
    if (!m) return fmi3Error;
    m->logging_on = loggingOn;
    return fmi3OK;
}

static void log_refusal(fmi3InstanceEnvironment environment, fmi3LogMessageCallback logMessage,
                        const char *message) {
    if (logMessage) logMessage(environment, fmi3Error, "logStatusError", message);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    char message[FAIL_MESSAGE_SIZE];
    ModelInstance *m;
    UNUSED(resourcePath);
    UNUSED(visible);
    UNUSED(earlyReturnAllowed); /* the FMU never returns early */
    UNUSED(requiredIntermediateVariables);
    UNUSED(nRequiredIntermediateVariables);
    UNUSED(intermediateUpdate);
    if (!instanceName || !*instanceName) instanceName = MODEL_NAME;
    if (!instantiationToken || strcmp(instantiationToken, MODEL_GUID) != 0) {
        snprintf(message, sizeof message,
                 "fmi3InstantiateCoSimulation: instantiation token %s does not match %s; rebuild the FMU",
                 instantiationToken ? instantiationToken : "(null)", MODEL_GUID);
        log_refusal(instanceEnvironment, logMessage, message);
        return NULL;
    }
    if (eventModeUsed) {
        snprintf(message, sizeof message, "fmi3InstantiateCoSimulation: %s has no event mode "
                 "(hasEventMode=\"false\"); instantiate it with eventModeUsed = false", MODEL_NAME);
        log_refusal(instanceEnvironment, logMessage, message);
        return NULL;
    }
    m = new_instance(instanceName, loggingOn);
    if (!m) return NULL;
    m->environment = instanceEnvironment;
    m->log_message = logMessage;
    publish(m);
    return m;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    UNUSED(instanceName);
    UNUSED(instantiationToken);
    UNUSED(resourcePath);
    UNUSED(visible);
    UNUSED(loggingOn);
    log_refusal(instanceEnvironment, logMessage,
                "fmi3InstantiateModelExchange: " MODEL_NAME " supports Co-Simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    UNUSED(instanceName);
    UNUSED(instantiationToken);
    UNUSED(resourcePath);
    UNUSED(visible);
    UNUSED(loggingOn);
    UNUSED(clockUpdate);
    UNUSED(lockPreemption);
    UNUSED(unlockPreemption);
    log_refusal(instanceEnvironment, logMessage,
                "fmi3InstantiateScheduledExecution: " MODEL_NAME " supports Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { free_instance(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    ModelInstance *m = live(instance);
    Status status;
    if (!ALLOWED(m, fmi3EnterInitializationMode)) return fmi3Error;
    status = setup_experiment(m, "fmi3EnterInitializationMode", toleranceDefined, tolerance, startTime,
                              stopTimeDefined, stopTime);
    if (status == fmi3OK) m->mode = MODE_INITIALIZATION;
    return status;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    ModelInstance *m = live(instance);
    if (!ALLOWED(m, fmi3ExitInitializationMode)) return fmi3Error;
    return exit_initialization(m, "fmi3ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    ModelInstance *m = live(instance);
    if (!ALLOWED(m, fmi3Terminate)) return fmi3Error;
    m->mode = MODE_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    ModelInstance *m = live(instance);
    if (!m) return fmi3Error;
    reset(m);
    return fmi3OK;
}

/* ---------------------------------------------------------------- get and set */
/* What Float64 value reference vr stands for: time (INDEX_TIME), a Real scalar, or a whole array
 * (ARRAY_FIRST, ARRAY_LENGTH of variables.h); its count of values, with the Real index of the first
 * in *first, or 0 when it is none of them (a later member of an array has no reference of its own). */
#define INDEX_TIME (-1)
static int float64_reference(fmi3ValueReference vr, int *first) {
    int k, a;
    if (vr == VR_TIME) {
        *first = INDEX_TIME;
        return 1;
    }
    if (vr - FIRST_REAL >= (unsigned int)N_REAL) return 0;
    k = (int)(vr - FIRST_REAL);
    *first = k;
    for (a = 0; a < N_ARRAYS; a++) {
        if (k == ARRAY_FIRST[a]) return ARRAY_LENGTH[a];
        if (k > ARRAY_FIRST[a] && k < ARRAY_FIRST[a] + ARRAY_LENGTH[a]) return 0;
    }
    return 1;
}

/* Refuses unless every reference is a Float64 variable (time only when `time_allowed`) and
 * together they hold nValues values. */
static Status check_float64(ModelInstance *m, const char *function, const fmi3ValueReference vr[], size_t nvr,
                            const void *values, size_t nValues, int time_allowed) {
    size_t i, total = 0;
    int first = 0, count;
    if (nvr > 0 && !vr) return fail(m, function, "null value reference array");
    if (nvr > 0 && !values) return fail(m, function, "null value array");
    for (i = 0; i < nvr; i++) {
        count = float64_reference(vr[i], &first);
        if (!count)
            return fail(m, function, "unknown value reference %u: the Float64 variables of %s are time (0) and "
                        "%u to %d, an array by the reference of its first element", (unsigned)vr[i], MODEL_NAME,
                        FIRST_REAL, (int)FIRST_REAL + N_REAL - 1);
        if (first == INDEX_TIME && !time_allowed)
            return fail(m, function, "time (value reference 0) is the independent variable and cannot be set; "
                        "give the start time to fmi3EnterInitializationMode");
        total += (size_t)count;
    }
    if (total != nValues)
        return fail(m, function, "%lu values for value references that hold %lu", (unsigned long)nValues,
                    (unsigned long)total);
    return fmi3OK;
}

/* The Real indices first .. first + count - 1, as the state machine's get and set take them. */
static const unsigned int *indices(int first, int count, unsigned int room[]) {
    int j;
    for (j = 0; j < count; j++) room[j] = (unsigned int)(first + j);
    return room;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    ModelInstance *m = live(instance);
    unsigned int room[N_REAL > 0 ? N_REAL : 1];
    size_t i, n = 0;
    int first = 0, count;
    if (!ALLOWED(m, fmi3GetFloat64)) return fmi3Error;
    if (check_float64(m, "fmi3GetFloat64", valueReferences, nValueReferences, values, nValues, 1) != fmi3OK)
        return fmi3Error;
    for (i = 0; i < nValueReferences; i++, n += (size_t)count) {
        count = float64_reference(valueReferences[i], &first);
        if (first == INDEX_TIME) values[n] = m->time;
        else if (get_reals(m, "fmi3GetFloat64", indices(first, count, room), (size_t)count, 0, values + n) != fmi3OK)
            return fmi3Error;
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    ModelInstance *m = live(instance);
    if (!ALLOWED(m, fmi3GetInt32)) return fmi3Error;
    if (check_scalars(m, "fmi3GetInt32", nValueReferences, nValues) != fmi3OK) return fmi3Error;
    return get_integers(m, "fmi3GetInt32", valueReferences, nValueReferences, FIRST_INTEGER, values);
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues) {
    ModelInstance *m = live(instance);
    size_t i;
    if (!ALLOWED(m, fmi3GetBoolean)) return fmi3Error;
    if (check_scalars(m, "fmi3GetBoolean", nValueReferences, nValues) != fmi3OK) return fmi3Error;
    if (check_refs(m, "fmi3GetBoolean", valueReferences, nValueReferences, FIRST_BOOLEAN, N_BOOLEAN, "Boolean") !=
        fmi3OK)
        return fmi3Error;
    if (nValueReferences > 0 && !values) return fail(m, "fmi3GetBoolean", "null value array");
    for (i = 0; i < nValueReferences; i++) values[i] = m->boolean[valueReferences[i] - FIRST_BOOLEAN] != 0;
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    ModelInstance *m = live(instance);
    unsigned int room[N_REAL > 0 ? N_REAL : 1];
    size_t i, n = 0;
    int first = 0, count;
    if (!ALLOWED(m, fmi3SetFloat64)) return fmi3Error;
    if (check_float64(m, "fmi3SetFloat64", valueReferences, nValueReferences, values, nValues, 0) != fmi3OK)
        return fmi3Error;
    for (i = 0; i < nValueReferences; i++, n += (size_t)count) {
        count = float64_reference(valueReferences[i], &first);
        if (set_reals(m, "fmi3SetFloat64", indices(first, count, room), (size_t)count, 0, values + n) != fmi3OK)
            return fmi3Error;
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    ModelInstance *m = live(instance);
    if (!ALLOWED(m, fmi3SetInt32)) return fmi3Error;
    if (check_scalars(m, "fmi3SetInt32", nValueReferences, nValues) != fmi3OK) return fmi3Error;
    return set_integers(m, "fmi3SetInt32", valueReferences, nValueReferences, FIRST_INTEGER, values);
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues) {
    ModelInstance *m = live(instance);
    size_t i;
    if (!ALLOWED(m, fmi3SetBoolean)) return fmi3Error;
    if (check_scalars(m, "fmi3SetBoolean", nValueReferences, nValues) != fmi3OK) return fmi3Error;
    if (check_boolean_set(m, "fmi3SetBoolean", valueReferences, nValueReferences, FIRST_BOOLEAN, values) != fmi3OK)
        return fmi3Error;
    for (i = 0; i < nValueReferences; i++) m->boolean[valueReferences[i] - FIRST_BOOLEAN] = values[i] ? 1 : 0;
    m->outputs_stale = 1;
    return fmi3OK;
}

/* The types this model has no variables of: a call with references names what is missing. */
static fmi3Status no_variables(fmi3Instance instance, const char *function, size_t nValueReferences,
                               const char *type) {
    ModelInstance *m = live(instance);
    if (!m) return fmi3Error;
    if (nValueReferences == 0) return fmi3OK;
    return fail(m, function, "%s has no %s variables", MODEL_NAME, type);
}

#define NO_VARIABLES(function, type, ctype, constness)                                                         \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference valueReferences[],                   \
                        size_t nValueReferences, constness ctype values[], size_t nValues) {                 \
        UNUSED(valueReferences);                                                                             \
        UNUSED(values);                                                                                      \
        UNUSED(nValues);                                                                                     \
        return no_variables(instance, #function, nValueReferences, type);                                    \
    }
#define NOTHING
NO_VARIABLES(fmi3GetFloat32, "Float32", fmi3Float32, NOTHING)
NO_VARIABLES(fmi3GetInt8, "Int8", fmi3Int8, NOTHING)
NO_VARIABLES(fmi3GetUInt8, "UInt8", fmi3UInt8, NOTHING)
NO_VARIABLES(fmi3GetInt16, "Int16", fmi3Int16, NOTHING)
NO_VARIABLES(fmi3GetUInt16, "UInt16", fmi3UInt16, NOTHING)
NO_VARIABLES(fmi3GetUInt32, "UInt32", fmi3UInt32, NOTHING)
NO_VARIABLES(fmi3GetInt64, "Int64", fmi3Int64, NOTHING)
NO_VARIABLES(fmi3GetUInt64, "UInt64", fmi3UInt64, NOTHING)
NO_VARIABLES(fmi3GetString, "String", fmi3String, NOTHING)
NO_VARIABLES(fmi3SetFloat32, "Float32", fmi3Float32, const)
NO_VARIABLES(fmi3SetInt8, "Int8", fmi3Int8, const)
NO_VARIABLES(fmi3SetUInt8, "UInt8", fmi3UInt8, const)
NO_VARIABLES(fmi3SetInt16, "Int16", fmi3Int16, const)
NO_VARIABLES(fmi3SetUInt16, "UInt16", fmi3UInt16, const)
NO_VARIABLES(fmi3SetUInt32, "UInt32", fmi3UInt32, const)
NO_VARIABLES(fmi3SetInt64, "Int64", fmi3Int64, const)
NO_VARIABLES(fmi3SetUInt64, "UInt64", fmi3UInt64, const)
NO_VARIABLES(fmi3SetString, "String", fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    UNUSED(valueReferences);
    UNUSED(valueSizes);
    UNUSED(values);
    UNUSED(nValues);
    return no_variables(instance, "fmi3GetBinary", nValueReferences, "Binary");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    UNUSED(valueReferences);
    UNUSED(valueSizes);
    UNUSED(values);
    UNUSED(nValues);
    return no_variables(instance, "fmi3SetBinary", nValueReferences, "Binary");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    UNUSED(valueReferences);
    UNUSED(values);
    return no_variables(instance, "fmi3GetClock", nValueReferences, "Clock");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    UNUSED(valueReferences);
    UNUSED(values);
    return no_variables(instance, "fmi3SetClock", nValueReferences, "Clock");
}

/* ---------------------------------------------------------------- stepping */
fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
    ModelInstance *m = live(instance);
    Status status;
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    if (!ALLOWED(m, fmi3DoStep)) return fmi3Error;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return fail(m, "fmi3DoStep", "null pointer for an output argument");
    status = do_step(m, "fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = m->time;
    return status;
}

/* ---------------------------------------------------------------- unsupported capabilities */
static fmi3Status unsupported(fmi3Instance instance, const char *function, const char *why) {
    return fail(live(instance), function, "%s", why);
}
#define NOT_SUPPORTED "not supported"
#define NO_EVENT_MODE "not supported: a Co-Simulation FMU without event mode (hasEventMode=\"false\")"
#define ONLY_CO_SIMULATION "not supported: the FMU is Co-Simulation only"

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterEventMode", NO_EVENT_MODE);
}
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterStepMode", NO_EVENT_MODE);
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return unsupported(instance, "fmi3EvaluateDiscreteStates", NO_EVENT_MODE);
}
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    UNUSED(discreteStatesNeedUpdate);
    UNUSED(terminateSimulation);
    UNUSED(nominalsOfContinuousStatesChanged);
    UNUSED(valuesOfContinuousStatesChanged);
    UNUSED(nextEventTimeDefined);
    UNUSED(nextEventTime);
    return unsupported(instance, "fmi3UpdateDiscreteStates", NO_EVENT_MODE);
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    UNUSED(valueReference);
    UNUSED(nDependencies);
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies", NOT_SUPPORTED);
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    UNUSED(dependent);
    UNUSED(elementIndicesOfDependent);
    UNUSED(independents);
    UNUSED(elementIndicesOfIndependents);
    UNUSED(dependencyKinds);
    UNUSED(nDependencies);
    return unsupported(instance, "fmi3GetVariableDependencies", NOT_SUPPORTED);
}
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    UNUSED(FMUState);
    return unsupported(instance, "fmi3GetFMUState", NOT_SUPPORTED);
}
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    UNUSED(FMUState);
    return unsupported(instance, "fmi3SetFMUState", NOT_SUPPORTED);
}
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    UNUSED(FMUState);
    return unsupported(instance, "fmi3FreeFMUState", NOT_SUPPORTED);
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    UNUSED(FMUState);
    UNUSED(size);
    return unsupported(instance, "fmi3SerializedFMUStateSize", NOT_SUPPORTED);
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    UNUSED(FMUState);
    UNUSED(serializedState);
    UNUSED(size);
    return unsupported(instance, "fmi3SerializeFMUState", NOT_SUPPORTED);
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    UNUSED(serializedState);
    UNUSED(size);
    UNUSED(FMUState);
    return unsupported(instance, "fmi3DeserializeFMUState", NOT_SUPPORTED);
}

#define DERIVATIVE(function)                                                                                   \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,        \
                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],          \
                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {                      \
        UNUSED(unknowns);                                                                                    \
        UNUSED(nUnknowns);                                                                                   \
        UNUSED(knowns);                                                                                      \
        UNUSED(nKnowns);                                                                                     \
        UNUSED(seed);                                                                                        \
        UNUSED(nSeed);                                                                                       \
        UNUSED(sensitivity);                                                                                 \
        UNUSED(nSensitivity);                                                                                \
        return unsupported(instance, #function, NOT_SUPPORTED);                                              \
    }
DERIVATIVE(fmi3GetDirectionalDerivative)
DERIVATIVE(fmi3GetAdjointDerivative)

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterConfigurationMode", "not supported: the FMU has no structural parameters");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3ExitConfigurationMode", "not supported: the FMU has no structural parameters");
}

/* Clocks: the FMU has none. */
#define NO_CLOCKS "not supported: the FMU has no clocks"
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(intervals);
    UNUSED(qualifiers);
    return unsupported(instance, "fmi3GetIntervalDecimal", NO_CLOCKS);
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(counters);
    UNUSED(resolutions);
    UNUSED(qualifiers);
    return unsupported(instance, "fmi3GetIntervalFraction", NO_CLOCKS);
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(shifts);
    return unsupported(instance, "fmi3GetShiftDecimal", NO_CLOCKS);
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(counters);
    UNUSED(resolutions);
    return unsupported(instance, "fmi3GetShiftFraction", NO_CLOCKS);
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(intervals);
    return unsupported(instance, "fmi3SetIntervalDecimal", NO_CLOCKS);
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(counters);
    UNUSED(resolutions);
    return unsupported(instance, "fmi3SetIntervalFraction", NO_CLOCKS);
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(shifts);
    return unsupported(instance, "fmi3SetShiftDecimal", NO_CLOCKS);
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(counters);
    UNUSED(resolutions);
    return unsupported(instance, "fmi3SetShiftFraction", NO_CLOCKS);
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    UNUSED(clockReference);
    UNUSED(activationTime);
    return unsupported(instance, "fmi3ActivateModelPartition", ONLY_CO_SIMULATION);
}

/* Model Exchange: not provided. */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return unsupported(instance, "fmi3EnterContinuousTimeMode", ONLY_CO_SIMULATION);
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    UNUSED(noSetFMUStatePriorToCurrentPoint);
    UNUSED(enterEventMode);
    UNUSED(terminateSimulation);
    return unsupported(instance, "fmi3CompletedIntegratorStep", ONLY_CO_SIMULATION);
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    UNUSED(time);
    return unsupported(instance, "fmi3SetTime", ONLY_CO_SIMULATION);
}
#define STATE_VECTOR(function, constness)                                                                      \
    fmi3Status function(fmi3Instance instance, constness fmi3Float64 values[], size_t n) {                    \
        UNUSED(values);                                                                                      \
        UNUSED(n);                                                                                           \
        return unsupported(instance, #function, ONLY_CO_SIMULATION);                                         \
    }
STATE_VECTOR(fmi3SetContinuousStates, const)
STATE_VECTOR(fmi3GetContinuousStateDerivatives, NOTHING)
STATE_VECTOR(fmi3GetEventIndicators, NOTHING)
STATE_VECTOR(fmi3GetContinuousStates, NOTHING)
STATE_VECTOR(fmi3GetNominalsOfContinuousStates, NOTHING)
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    UNUSED(nEventIndicators);
    return unsupported(instance, "fmi3GetNumberOfEventIndicators", ONLY_CO_SIMULATION);
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    UNUSED(nContinuousStates);
    return unsupported(instance, "fmi3GetNumberOfContinuousStates", ONLY_CO_SIMULATION);
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    UNUSED(valueReferences);
    UNUSED(nValueReferences);
    UNUSED(orders);
    UNUSED(values);
    UNUSED(nValues);
    return unsupported(instance, "fmi3GetOutputDerivatives", NOT_SUPPORTED);
}
