/* The stepping loop of the step benchmark: `count` macro steps of `n` components, each stepped
 * by its own function of fmi2DoStep's signature (an FMU's fmi2DoStep, or a model's equations
 * called directly), in the order given. Returns 0, or the first status above Warning. */
#include <stddef.h>

typedef int (*DoStep)(void *, double, double, int);

int step_all(DoStep const *step, void *const *component, int n, long count, double dt) {
    long k;
    int i, status;
    for (k = 0; k < count; k++) {
        for (i = 0; i < n; i++) {
            status = step[i](component[i], (double)k * dt, dt, 1);
            if (status > 1) return status;
        }
    }
    return 0;
}
