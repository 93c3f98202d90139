/* An FMI 2.0 Co-Simulation model with a variable of every FMI 2.0 type, for the tests: Real,
 * Integer, Boolean and Enumeration inputs and outputs, String and other parameters, a String
 * output (tag, the label), a String input (note), and a state that changes at events (a counter
 * that steps each time an integrator crosses a threshold).
 *
 * Per doStep(t, h), from the inputs set before it:
 *   x += gain u h; when x >= threshold: counter += 1 and x -= threshold (the event);
 *   k_sum += k_in; flips += 1 while b_in; above = (counter odd) xor invert; mode_out = mode_in.
 * Outputs depend on the state only (no direct feedthrough). */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

enum { R_U, R_X, R_GAIN, R_THRESHOLD, N_REAL };
enum { I_K_IN, I_K_SUM, I_COUNTER, I_START_COUNT, I_FLIPS, I_MODE_IN, I_MODE_OUT, N_INTEGER };
enum { B_IN, B_ABOVE, B_INVERT, N_BOOLEAN };
enum { S_LABEL, S_TAG, S_NOTE, N_STRING }; /* tag: an output that reads the label; note: an input */

typedef struct {
    fmi2Real r[N_REAL];
    fmi2Integer i[N_INTEGER];
    fmi2Boolean b[N_BOOLEAN];
    char label[64];
    char note[64];
    const fmi2CallbackFunctions *callbacks;
    fmi2String name;
} Model;

static void defaults(Model *m) {
    memset(m->r, 0, sizeof m->r);
    memset(m->i, 0, sizeof m->i);
    memset(m->b, 0, sizeof m->b);
    m->r[R_GAIN] = 1.0;
    m->r[R_THRESHOLD] = 0.05;
    m->i[I_MODE_IN] = m->i[I_MODE_OUT] = 1;
    strcpy(m->label, "plain");
    strcpy(m->note, "none");
}

static void settle(Model *m) {
    m->b[B_ABOVE] = (m->i[I_COUNTER] % 2 == 1) != (m->b[B_INVERT] != 0);
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *callbacks, fmi2Boolean visible, fmi2Boolean logging) {
    Model *m;
    (void)resources, (void)visible, (void)logging;
    if (type != fmi2CoSimulation || strcmp(guid, "{quadcosim-types2}") != 0)
        return NULL;
    m = calloc(1, sizeof *m);
    m->callbacks = callbacks;
    m->name = name;
    defaults(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    (void)c, (void)on, (void)n, (void)categories;
    return fmi2OK;
}
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    (void)c, (void)tolerance_defined, (void)tolerance, (void)start, (void)stop_defined, (void)stop;
    return fmi2OK;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Model *m = c;
    m->i[I_COUNTER] = m->i[I_START_COUNT];
    settle(m);
    return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { defaults(c); return fmi2OK; }

#define ACCESS(Type, array, count)                                                                          \
    fmi2Status fmi2Get##Type(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2##Type v[]) {      \
        Model *m = c;                                                                                        \
        for (size_t k = 0; k < n; k++) {                                                                     \
            if (vr[k] >= count) return fmi2Error;                                                            \
            v[k] = m->array[vr[k]];                                                                          \
        }                                                                                                    \
        return fmi2OK;                                                                                       \
    }                                                                                                        \
    fmi2Status fmi2Set##Type(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2##Type v[]) { \
        Model *m = c;                                                                                        \
        for (size_t k = 0; k < n; k++) {                                                                     \
            if (vr[k] >= count) return fmi2Error;                                                            \
            m->array[vr[k]] = v[k];                                                                          \
        }                                                                                                    \
        return fmi2OK;                                                                                       \
    }
ACCESS(Real, r, N_REAL)
ACCESS(Integer, i, N_INTEGER)
ACCESS(Boolean, b, N_BOOLEAN)

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    Model *m = c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= N_STRING) return fmi2Error;
        v[k] = vr[k] == S_NOTE ? m->note : m->label;
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    Model *m = c;
    for (size_t k = 0; k < n; k++) {
        char *into = vr[k] == S_LABEL ? m->label : vr[k] == S_NOTE ? m->note : NULL;
        if (into == NULL || strlen(v[k]) >= sizeof m->label) return fmi2Error;
        strcpy(into, v[k]);
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_set_prior) {
    Model *m = c;
    (void)t, (void)no_set_prior;
#ifdef LYING_STEP /* the tests' liar: from t = 0.1 s its step returns -1, which is no FMI status */
    if (t >= 0.1 - 1e-9)
        return (fmi2Status)-1;
#endif
    m->r[R_X] += m->r[R_GAIN] * m->r[R_U] * h;
    if (m->r[R_X] >= m->r[R_THRESHOLD]) {
        m->i[I_COUNTER] += 1;
        m->r[R_X] -= m->r[R_THRESHOLD];
    }
    m->i[I_K_SUM] += m->i[I_K_IN];
    if (m->b[B_IN])
        m->i[I_FLIPS] += 1;
    m->i[I_MODE_OUT] = m->i[I_MODE_IN];
    settle(m);
    return fmi2OK;
}
