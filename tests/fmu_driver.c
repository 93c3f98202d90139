/* Steps FMUs' shared libraries directly, without fmpy: the same program is compiled for Linux
 * (dlopen) and for Windows (mingw-w64, LoadLibrary, run under Wine), so that the binaries of one
 * FMU for both platforms are driven by the same calls and their outputs compared bit for bit.
 *
 * Usage: fmu_driver PLAN. The plan is whitespace-separated text, one FMU after another:
 *   FMI_VERSION LIBRARY MODEL_IDENTIFIER TOKEN STEPS STEP_SIZE
 *   N_INPUTS  (VR VALUE) * N_INPUTS
 *   N_OUTPUTS N_VALUES VR * N_OUTPUTS
 *   OUTPUT_FILE
 * Each FMU is instantiated (Co-Simulation), initialised at t = 0 with the inputs set, stepped
 * STEPS times with them held; its Real outputs at t = 0 and after every step are written to
 * OUTPUT_FILE as native doubles, one row of N_VALUES per instant (an FMI 3.0 array output is one
 * reference of several values; in FMI 2.0, N_VALUES is N_OUTPUTS). Paths hold no spaces. Exit status 1 on
 * the first refusal, with the FMU's messages on standard error. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) ((void *)LoadLibraryA(path))
#define SYMBOL(library, name) ((void *)GetProcAddress((HMODULE)(library), name))
#else
#include <dlfcn.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(library, name) dlsym(library, name)
#endif

#define MAX_VARIABLES 256
#define MAX_TEXT 1024

static void logger2(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status,
                    fmi2String category, fmi2String message, ...) {
    va_list args;
    (void)environment;
    (void)category;
    fprintf(stderr, "%s [status %d]: ", instance, (int)status);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static void logger3(fmi3InstanceEnvironment environment, fmi3Status status, fmi3String category,
                    fmi3String message) {
    (void)environment;
    (void)category;
    fprintf(stderr, "[status %d]: %s\n", (int)status, message);
}

static void *symbol(void *library, const char *name) {
    void *found = SYMBOL(library, name);
    if (!found) {
        fprintf(stderr, "the library exports no %s\n", name);
        exit(1);
    }
    return found;
}

#define CHECK(call)                                                                                \
    do {                                                                                           \
        int status_ = (int)(call);                                                                 \
        if (status_ > 1) {                                                                         \
            fprintf(stderr, "%s returned status %d\n", #call, status_);                            \
            exit(1);                                                                               \
        }                                                                                          \
    } while (0)

typedef struct {
    int version, steps, n_in, n_out, n_values;
    char library[MAX_TEXT], identifier[MAX_TEXT], token[MAX_TEXT], output[MAX_TEXT];
    double h, in_value[MAX_VARIABLES];
    unsigned int in_vr[MAX_VARIABLES], out_vr[MAX_VARIABLES];
} Plan;

static int read_plan(FILE *file, Plan *p) {
    int i;
    if (fscanf(file, "%d %1023s %1023s %1023s %d %lf", &p->version, p->library, p->identifier, p->token,
               &p->steps, &p->h) != 6)
        return 0;
    if (fscanf(file, "%d", &p->n_in) != 1 || p->n_in < 0 || p->n_in > MAX_VARIABLES) return -1;
    for (i = 0; i < p->n_in; i++)
        if (fscanf(file, "%u %lf", &p->in_vr[i], &p->in_value[i]) != 2) return -1;
    if (fscanf(file, "%d %d", &p->n_out, &p->n_values) != 2 || p->n_out < 1 || p->n_out > MAX_VARIABLES ||
        p->n_values < p->n_out || p->n_values > MAX_VARIABLES || (p->version == 2 && p->n_values != p->n_out))
        return -1;
    for (i = 0; i < p->n_out; i++)
        if (fscanf(file, "%u", &p->out_vr[i]) != 1) return -1;
    return fscanf(file, "%1023s", p->output) == 1 ? 1 : -1;
}

static void run2(void *library, const Plan *p, FILE *out) {
    fmi2CallbackFunctions callbacks = {logger2, calloc, free, NULL, NULL};
    fmi2Real values[MAX_VARIABLES];
    fmi2Component c = ((fmi2InstantiateTYPE *)symbol(library, "fmi2Instantiate"))(
        p->identifier, fmi2CoSimulation, p->token, "", &callbacks, fmi2False, fmi2False);
    int k;
    if (!c) {
        fprintf(stderr, "fmi2Instantiate refused %s\n", p->identifier);
        exit(1);
    }
    CHECK(((fmi2SetupExperimentTYPE *)symbol(library, "fmi2SetupExperiment"))(c, fmi2False, 0.0, 0.0, fmi2False,
                                                                              0.0));
    CHECK(((fmi2EnterInitializationModeTYPE *)symbol(library, "fmi2EnterInitializationMode"))(c));
    CHECK(((fmi2SetRealTYPE *)symbol(library, "fmi2SetReal"))(c, p->in_vr, p->n_in, p->in_value));
    CHECK(((fmi2ExitInitializationModeTYPE *)symbol(library, "fmi2ExitInitializationMode"))(c));
    for (k = 0; k <= p->steps; k++) {
        if (k > 0)
            CHECK(((fmi2DoStepTYPE *)symbol(library, "fmi2DoStep"))(c, (k - 1) * p->h, p->h, fmi2True));
        CHECK(((fmi2GetRealTYPE *)symbol(library, "fmi2GetReal"))(c, p->out_vr, p->n_out, values));
        fwrite(values, sizeof(double), (size_t)p->n_out, out);
    }
    CHECK(((fmi2TerminateTYPE *)symbol(library, "fmi2Terminate"))(c));
    ((fmi2FreeInstanceTYPE *)symbol(library, "fmi2FreeInstance"))(c);
}

static void run3(void *library, const Plan *p, FILE *out) {
    fmi3Float64 values[MAX_VARIABLES];
    fmi3Boolean event, terminate, early;
    fmi3Float64 last;
    fmi3Instance c = ((fmi3InstantiateCoSimulationTYPE *)symbol(library, "fmi3InstantiateCoSimulation"))(
        p->identifier, p->token, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL, logger3, NULL);
    int k;
    if (!c) {
        fprintf(stderr, "fmi3InstantiateCoSimulation refused %s\n", p->identifier);
        exit(1);
    }
    CHECK(((fmi3EnterInitializationModeTYPE *)symbol(library, "fmi3EnterInitializationMode"))(
        c, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    CHECK(((fmi3SetFloat64TYPE *)symbol(library, "fmi3SetFloat64"))(c, p->in_vr, p->n_in, p->in_value, p->n_in));
    CHECK(((fmi3ExitInitializationModeTYPE *)symbol(library, "fmi3ExitInitializationMode"))(c));
    for (k = 0; k <= p->steps; k++) {
        if (k > 0)
            CHECK(((fmi3DoStepTYPE *)symbol(library, "fmi3DoStep"))(c, (k - 1) * p->h, p->h, fmi3True, &event,
                                                                    &terminate, &early, &last));
        CHECK(((fmi3GetFloat64TYPE *)symbol(library, "fmi3GetFloat64"))(c, p->out_vr, p->n_out, values,
                                                                          p->n_values));
        fwrite(values, sizeof(double), (size_t)p->n_values, out);
    }
    CHECK(((fmi3TerminateTYPE *)symbol(library, "fmi3Terminate"))(c));
    ((fmi3FreeInstanceTYPE *)symbol(library, "fmi3FreeInstance"))(c);
}

int main(int argc, char **argv) {
    static Plan plan;
    FILE *file, *out;
    void *library;
    int read;
    if (argc != 2 || !(file = fopen(argv[1], "r"))) {
        fprintf(stderr, "usage: fmu_driver PLAN (a readable file)\n");
        return 2;
    }
    while ((read = read_plan(file, &plan)) == 1) {
        if (!(library = LOAD(plan.library))) {
            fprintf(stderr, "cannot load %s\n", plan.library);
            return 1;
        }
        if (!(out = fopen(plan.output, "wb"))) {
            fprintf(stderr, "cannot write %s\n", plan.output);
            return 1;
        }
        if (plan.version == 3) run3(library, &plan, out);
        else run2(library, &plan, out);
        fclose(out);
    }
    fclose(file);
    if (read < 0) {
        fprintf(stderr, "%s: a plan entry is malformed\n", argv[1]);
        return 2;
    }
    return 0;
}
