/* Barometer: the static pressure of the International Standard Atmosphere's troposphere at the
 * body's altitude, through a first-order lag of the sensor's port.
 *
 *   h = h0 - p_z
 *   p_s(h) = p_sea (1 - L h / T_sea)^(g M / (R L))      sea_level_pressure, sea_level_temperature
 *   tau dp/dt = p_s(h) - p        advanced exactly over a step, p_z held
 *
 * The sensor starts settled: p = p_s at the altitude of its initial input.
 */
#include <math.h>

#include "variables.h"

#define R(name) (m->real[VR_##name])
#define STANDARD_GRAVITY 9.80665 /* m/s2 */
#define MOLAR_MASS_AIR 0.0289644 /* kg/mol, dry air */
#define GAS_CONSTANT 8.3144598   /* J/(mol K) */

typedef struct {
    double pressure; /* measured static pressure (Pa) */
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

/* Static pressure at the present altitude, in *p; 0 (logged) above the troposphere's top. */
static int static_pressure(ModelInstance *m, double *p) {
    double altitude = R(h0) - R(p_z), base = 1.0 - R(lapse_rate) * altitude / R(sea_level_temperature);
    if (!(base > 0.0)) {
        log_error(m, "altitude h0 - p_z = %g m is at or above %g m, where the troposphere ends (sea_level_temperature "
                     "/ lapse_rate); check p_z and h0", altitude, R(sea_level_temperature) / R(lapse_rate));
        return 0;
    }
    *p = R(sea_level_pressure) * pow(base, STANDARD_GRAVITY * MOLAR_MASS_AIR / (GAS_CONSTANT * R(lapse_rate)));
    return 1;
}

Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    if (!(R(sea_level_pressure) > 0.0) || !isfinite(R(sea_level_pressure))) {
        log_error(m, "parameter sea_level_pressure = %g N/m2 must be positive and finite", R(sea_level_pressure));
        return STATUS_ERROR;
    }
    if (!(R(sea_level_temperature) > 0.0) || !isfinite(R(sea_level_temperature))) {
        log_error(m, "parameter sea_level_temperature = %g K must be positive and finite", R(sea_level_temperature));
        return STATUS_ERROR;
    }
    if (!(R(lapse_rate) > 0.0) || !isfinite(R(lapse_rate))) {
        log_error(m, "parameter lapse_rate = %g K/m must be positive and finite (the troposphere cools with "
                     "altitude)", R(lapse_rate));
        return STATUS_ERROR;
    }
    if (!(R(tau) > 0.0) || !isfinite(R(tau))) {
        log_error(m, "parameter tau = %g s must be positive and finite", R(tau));
        return STATUS_ERROR;
    }
    return static_pressure(m, &d->pressure) ? STATUS_OK : STATUS_ERROR;
}

Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    double settled;
    (void)t;
    if (!static_pressure(m, &settled)) return STATUS_ERROR;
    d->pressure = settled + (d->pressure - settled) * exp(-h / R(tau));
    return STATUS_OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    R(altitude) = R(h0) - R(p_z);
    R(pressure) = d->pressure;
}
