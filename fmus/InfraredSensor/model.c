/* InfraredSensor: a fixed-wing in coordinated turns, its infrared horizon sensor and its GPS
 * turn rate ("Calibration d'un récepteur Infra-Rouge pour Micro Drone", Paparazzi, 2004).
 *
 *   r = g tan(phi) / V,   dpsi/dt = r
 *   a(t) = a0 (1 + day_a t + temp_a sin(2 pi t / T) + cloud_a c(t))      (day rates per second)
 *   b(t) = b0 + day_b t + temp_b sin(2 pi t / T) + cloud_b c(t)
 *   IR_k = a(t_k) r(t_k) + b(t_k) + n_IR
 *   GPS_k = (psi_m[k - D] - psi_m[k - D - W]) / window,   psi_m = psi + n_psi
 *
 * c(t) in [0, 1] is the cloud cover: sin^2 ramps in and out around a plateau. D and W are the
 * delay and the window in samples. Outputs are sampled at t_k = k / sample_rate and held, as
 * in the IMU: the sample at t_k follows the inputs until a step leaves t_k. phi is held over a
 * step, so the heading is advanced exactly. Noise sample k of a channel is a pure function of
 * (seed, k, channel): streams do not depend on the co-simulation step.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "noise.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])
#define HISTORY 4096 /* GPS heading samples kept: (delay + window) * sample_rate at most */
#define HALF_PI 1.5707963267948966
#define WHOLE_SAMPLES_TOLERANCE 1e-9 /* relative: a duration counts as a whole number of samples */
#define TWO_PI 6.283185307179586

enum { CH_IR = 0, CH_HEADING = 1 };

typedef struct {
    int64_t next_sample; /* first instant not yet final */
    int64_t current;     /* instant of the sample the outputs hold */
    int64_t first;       /* first sample of the run */
    int delay, window;   /* GPS delay and window, in samples */
    double psi;          /* heading at the model time (rad) */
    double heading[HISTORY]; /* measured heading of sample k at k % HISTORY */
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

static double turn_rate(ModelInstance *m) { return R(gravity) * tan(R(phi)) / R(airspeed); }

static double cloud_cover(ModelInstance *m, double t) {
    double ramp = R(cloud_ramp), in = t - R(cloud_start), out = in - ramp - R(cloud_duration), s;
    if (in <= 0.0 || out >= ramp) return 0.0;
    if (in < ramp) {
        s = sin(HALF_PI * in / ramp);
        return s * s;
    }
    if (out <= 0.0) return 1.0;
    s = cos(HALF_PI * out / ramp);
    return s * s;
}

/* True a and b at time t. */
static void calibration(ModelInstance *m, double t, double *a, double *b) {
    double wave, cloud;
    if (!m->boolean[VB_drift_enabled]) {
        *a = R(ir_gain);
        *b = R(ir_offset);
        return;
    }
    wave = sin(TWO_PI * t / R(temperature_period));
    cloud = cloud_cover(m, t);
    *a = R(ir_gain) * (1.0 + R(gain_day_rate) * t + R(gain_temperature) * wave + R(gain_cloud) * cloud);
    *b = R(ir_offset) + R(offset_day_rate) * t + R(offset_temperature) * wave + R(offset_cloud) * cloud;
}

/* Slot of sample k in the heading history; k < 0 when the FMU starts before t = 0. */
static int slot(int64_t k) { return (int)(((k % HISTORY) + HISTORY) % HISTORY); }

/* Sample k, at time t_k, with the heading psi there. */
static void take_sample(ModelInstance *m, Data *d, int64_t k, double t, double psi) {
    int noisy = m->boolean[VB_noise_enabled], seed = m->integer[VI_seed];
    double a, b, r = turn_rate(m);
    d->current = k;
    calibration(m, t, &a, &b);
    R(ir) = a * r + b + (noisy ? R(ir_noise) * gaussian(seed, k, CH_IR) : 0.0);
    d->heading[slot(k)] = psi + (noisy ? R(gps_heading_noise) * gaussian(seed, k, CH_HEADING) : 0.0);
    if (k - d->first >= d->delay + d->window) {
        R(gps_turn_rate) = (d->heading[slot(k - d->delay)] - d->heading[slot(k - d->delay - d->window)]) /
                           R(gps_window);
        R(gps_valid) = 1.0;
    } else {
        R(gps_turn_rate) = 0.0;
        R(gps_valid) = 0.0;
    }
}

/* A whole number of samples in `seconds`, or -1; a double, so that a huge duration is compared
 * with the history before it is ever converted to an integer. */
static double samples(ModelInstance *m, double seconds) {
    double n = seconds * R(sample_rate);
    if (!(n >= 0.0) || !isfinite(n) || fabs(n - floor(n + 0.5)) > WHOLE_SAMPLES_TOLERANCE * (1.0 + n)) return -1.0;
    return floor(n + 0.5);
}

static int bank_ok(ModelInstance *m) {
    if (fabs(R(phi)) < HALF_PI) return 1;
    log_error(m, "bank angle phi = %g rad is at or beyond +-pi/2 (90 deg): a coordinated turn needs "
                 "|phi| < pi/2; check the bank profile", R(phi));
    return 0;
}

Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    if (!(R(sample_rate) > 0.0) || !isfinite(R(sample_rate))) {
        log_error(m, "parameter sample_rate = %g Hz must be positive and finite", R(sample_rate));
        return STATUS_ERROR;
    }
    if (!(R(airspeed) > 0.0) || !isfinite(R(airspeed))) {
        log_error(m, "parameter airspeed = %g m/s must be positive and finite (r = g tan(phi) / V)", R(airspeed));
        return STATUS_ERROR;
    }
    if (!(R(gravity) > 0.0)) {
        log_error(m, "parameter gravity = %g m/s2 must be positive", R(gravity));
        return STATUS_ERROR;
    }
    if (!(R(temperature_period) > 0.0) || !(R(cloud_ramp) > 0.0) || !(R(cloud_duration) >= 0.0)) {
        log_error(m, "temperature_period and cloud_ramp must be positive and cloud_duration non-negative");
        return STATUS_ERROR;
    }
    if (!(R(ir_noise) >= 0.0) || !(R(gps_heading_noise) >= 0.0)) {
        log_error(m, "noise levels ir_noise and gps_heading_noise must be non-negative");
        return STATUS_ERROR;
    }
    double delay = samples(m, R(gps_delay)), window = samples(m, R(gps_window));
    if (delay < 0.0 || window < 1.0) {
        log_error(m, "gps_delay = %g s and gps_window = %g s must be whole numbers of sample periods "
                     "(1 / sample_rate = %g s), the window at least one", R(gps_delay), R(gps_window),
                  1.0 / R(sample_rate));
        return STATUS_ERROR;
    }
    if (delay + window >= (double)HISTORY) {
        log_error(m, "gps_delay + gps_window = %g s spans %.3g samples, more than the %d kept; shorten them",
                  R(gps_delay) + R(gps_window), delay + window, HISTORY - 1);
        return STATUS_ERROR;
    }
    d->delay = (int)delay;
    d->window = (int)window;
    if (!bank_ok(m)) return STATUS_ERROR;
    d->psi = R(psi0);
    d->next_sample = (int64_t)ceil(m->time * R(sample_rate) - SAMPLE_INSTANT_TOLERANCE);
    d->first = d->next_sample;
    d->current = d->first - 1;
    return STATUS_OK;
}

Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    double r, tk, last = ceil((t + h) * R(sample_rate) - SAMPLE_INSTANT_TOLERANCE);
    int64_t end;
    /* instants in [t, t + h) become final, with phi held over the step */
    if (!bank_ok(m)) return STATUS_ERROR;
    if (!work_allowed(m, last - (double)d->next_sample, h,
                      "take shorter communication steps or a lower sample_rate", "samples at sample_rate = %g Hz",
                      R(sample_rate)))
        return STATUS_ERROR;
    end = (int64_t)last;
    r = turn_rate(m);
    for (; d->next_sample < end; d->next_sample++) {
        if (!(d->current == d->next_sample && !m->outputs_stale)) {
            tk = (double)d->next_sample / R(sample_rate);
            take_sample(m, d, d->next_sample, tk, d->psi + r * (tk - t));
        }
    }
    d->psi += r * h;
    return STATUS_OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    double position = m->time * R(sample_rate), a, b;
    int64_t k = (int64_t)floor(position + SAMPLE_INSTANT_TOLERANCE);
    calibration(m, m->time, &a, &b);
    R(a) = a;
    R(b) = b;
    R(psi) = d->psi;
    R(r) = fabs(R(phi)) < HALF_PI ? turn_rate(m) : NAN;
    /* at a sample instant not yet final, the sample follows the present input */
    if (k == d->next_sample && fabs(position - (double)k) < SAMPLE_INSTANT_TOLERANCE) take_sample(m, d, k, m->time, d->psi);
}
