/* IMU: accelerometer and gyrometer sampled at sample_rate, magnetometer at mag_sample_rate,
 * each held between its samples.
 *
 *   acc = f_B + b_a + a_vib + n_a
 *   gyro = omega + b_g + n_g
 *   magneto = A R^T m_I + b_s + b_d + n_m      (Metge et al. 2013, eq. 1: soft iron A, hard iron b_s)
 *   R_reel = R(q)                               (with acc and gyro)
 *   a_vib = vibration_amplitude sum_n (omega_n / vibration_speed)^2 (cos phi_n, -s_n sin phi_n, 0)
 *
 * a_vib: the once-per-revolution vibration of rotor imbalance, a rotating in-plane acceleration
 * growing with the square of the rotor speed; phi_n is rotor n's angle, dphi_n/dt = omega_n,
 * phi_n(0) = 0, turning counter-clockwise seen from above when s_n = +1.
 *
 * The sample at t_k = k / rate uses the inputs at t_k: while the time is t_k it follows the
 * inputs as they are set, and it is final once a step leaves t_k. Instants inside a step see
 * the inputs held over the step. Noise sample k of channel c is a pure function of (seed, k, c),
 * so streams do not depend on the co-simulation step; its standard deviation is
 * density * sqrt(rate) of its sensor.
 * The input q is normalised when its norm is within QUATERNION_TOLERANCE of 1 (the rounding
 * of a recorded or integrated attitude); further off, the step is refused, since R(q) would
 * not be a rotation.
 */
#include <math.h>
#include <stdint.h>

#include "airframe.h"
#include "noise.h"
#include "quaternion.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])
#define RV(name) REAL_VECTOR(m, name)
#define QUATERNION_TOLERANCE 1e-3 /* largest | |q| - 1 | normalised rather than refused */
#define PI 3.141592653589793

enum { CH_ACC = 0, CH_GYRO = 3, CH_MAG = 6, CH_WALK_GYRO = 9, CH_WALK_ACC = 12 };

/* A sample clock: instants k / rate. */
typedef struct {
    int64_t next;    /* first instant not yet final */
    int64_t current; /* instant of the sample the outputs hold */
} Clock;

typedef struct {
    Clock inertial, magnetic;
    double gyro_bias[3], acc_bias[3];
    double phase[N_MOTORS]; /* rotor angles at the present time, rad, in [0, 2 pi) */
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

/* r = R(q / |q|): doStep refuses a q far from unit norm, q = 0 among them. */
static void unit_rotation(const double *q, double r[9]) {
    double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), unit[4];
    int i;
    for (i = 0; i < 4; i++) unit[i] = norm > 0.0 ? q[i] / norm : (i == 0);
    rotation_from_quaternion(unit, r);
}

/* Rotor-imbalance acceleration at instant `at` (s), the rotor speeds held since m->time. */
static void vibration(ModelInstance *m, const Data *d, double at, double out[3]) {
    const double *w = RV(omega_r);
    int n;
    out[0] = out[1] = out[2] = 0.0;
    if (R(vibration_amplitude) == 0.0) return;
    for (n = 0; n < N_MOTORS; n++) {
        double phi = d->phase[n] + w[n] * (at - m->time), ratio = w[n] / R(vibration_speed);
        double a = R(vibration_amplitude) * ratio * ratio;
        out[0] += a * cos(phi);
        out[1] -= a * SPIN[n] * sin(phi);
    }
}

/* Accelerometer, gyrometer, R_reel and true biases at instant k / sample_rate. */
static void take_inertial(ModelInstance *m, Data *d, int64_t k) {
    const double *q = RV(q), *w = RV(omega), *f = RV(f);
    double r[9], sd_acc = 0.0, sd_gyro = 0.0, vib[3];
    int noisy = m->boolean[VB_noise_enabled], biased = m->boolean[VB_bias_enabled], seed = m->integer[VI_seed], i;
    d->inertial.current = k;
    unit_rotation(q, r);
    vibration(m, d, (double)k / R(sample_rate), vib);
    if (noisy) {
        double root_rate = sqrt(R(sample_rate));
        sd_acc = R(acc_noise_density) * root_rate;
        sd_gyro = R(gyro_noise_density) * root_rate;
    }
    for (i = 0; i < 3; i++) {
        RV(acc)[i] = f[i] + (biased ? d->acc_bias[i] : 0.0) + vib[i] +
                         (noisy ? sd_acc * gaussian(seed, k, CH_ACC + i) : 0.0);
        RV(gyro)[i] = w[i] + (biased ? d->gyro_bias[i] : 0.0) +
                          (noisy ? sd_gyro * gaussian(seed, k, CH_GYRO + i) : 0.0);
        RV(gyro_bias)[i] = biased ? d->gyro_bias[i] : 0.0;
        RV(acc_bias)[i] = biased ? d->acc_bias[i] : 0.0;
    }
    for (i = 0; i < LEN_R_reel; i++) RV(R_reel)[i] = r[i];
}

/* Magnetometer at instant k / mag_sample_rate. */
static void take_magnetic(ModelInstance *m, Data *d, int64_t k) {
    const double *q = RV(q), *bd = RV(b_d), *a = RV(A), *bs = RV(b_s), *mi = RV(m_I);
    double r[9], body[3], sd = 0.0;
    int noisy = m->boolean[VB_noise_enabled], i;
    d->magnetic.current = k;
    unit_rotation(q, r);
    if (noisy) sd = R(mag_noise_density) * sqrt(R(mag_sample_rate));
    for (i = 0; i < 3; i++) body[i] = r[i] * mi[0] + r[3 + i] * mi[1] + r[6 + i] * mi[2]; /* R^T m_I */
    for (i = 0; i < 3; i++)
        RV(magneto)[i] = a[3 * i] * body[0] + a[3 * i + 1] * body[1] + a[3 * i + 2] * body[2] + bs[i] +
                             bd[i] + (noisy ? sd * gaussian(m->integer[VI_seed], k, CH_MAG + i) : 0.0);
}

/* Inertial sample k is final: the biases walk on to sample k + 1. */
static void commit_inertial(ModelInstance *m, Data *d, int64_t k) {
    double root_dt = sqrt(1.0 / R(sample_rate));
    int seed = m->integer[VI_seed], i;
    if (R(gyro_bias_walk) == 0.0 && R(acc_bias_walk) == 0.0) return;
    for (i = 0; i < 3; i++) {
        d->gyro_bias[i] += R(gyro_bias_walk) * root_dt * gaussian(seed, k, CH_WALK_GYRO + i);
        d->acc_bias[i] += R(acc_bias_walk) * root_dt * gaussian(seed, k, CH_WALK_ACC + i);
    }
}

Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const char *rates[] = {"sample_rate", "mag_sample_rate", "vibration_speed"};
    const double values[] = {R(sample_rate), R(mag_sample_rate), R(vibration_speed)};
    const char *units[] = {"Hz", "Hz", "rad/s"};
    int i;
    for (i = 0; i < 3; i++) {
        if (!(values[i] > 0.0) || !isfinite(values[i])) {
            log_error(m, "parameter %s = %g %s must be positive and finite", rates[i], values[i], units[i]);
            return STATUS_ERROR;
        }
    }
    if (!(R(gyro_noise_density) >= 0.0) || !(R(acc_noise_density) >= 0.0) ||
        !(R(mag_noise_density) >= 0.0) || !(R(gyro_bias_walk) >= 0.0) || !(R(acc_bias_walk) >= 0.0)) {
        log_error(m, "noise densities and bias walks must be non-negative");
        return STATUS_ERROR;
    }
    if (!(R(vibration_amplitude) >= 0.0) || !isfinite(R(vibration_amplitude))) {
        log_error(m, "parameter vibration_amplitude = %g m/s2 must be non-negative and finite (0: off)",
                  R(vibration_amplitude));
        return STATUS_ERROR;
    }
    for (i = 0; i < 3; i++) {
        d->gyro_bias[i] = RV(b_g)[i];
        d->acc_bias[i] = RV(b_a)[i];
    }
    for (i = 0; i < N_MOTORS; i++) d->phase[i] = 0.0;
    d->inertial.next = (int64_t)ceil(m->time * R(sample_rate) - SAMPLE_INSTANT_TOLERANCE);
    d->magnetic.next = (int64_t)ceil(m->time * R(mag_sample_rate) - SAMPLE_INSTANT_TOLERANCE);
    d->inertial.current = d->magnetic.current = -1;
    return STATUS_OK;
}

/* Index one past the last instant of clock `rate` in [t, t + h), or -1 when too many. */
static int64_t end_of_step(ModelInstance *m, const Clock *c, double rate, const char *name, double t, double h) {
    double last = ceil((t + h) * rate - SAMPLE_INSTANT_TOLERANCE);
    if (!work_allowed(m, last - (double)c->next, h, "take shorter communication steps or a lower rate",
                      "samples at %s = %g Hz", name, rate))
        return -1;
    return (int64_t)last;
}

Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    /* instants in [t, t + h) become final, with the inputs held over the step */
    const double *q = RV(q);
    double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    int64_t inertial_end, magnetic_end;
    if (!(fabs(norm - 1.0) <= QUATERNION_TOLERANCE)) {
        log_error(m, FMI_NAME(DoStep) ": the attitude q = (%g, %g, %g, %g) at t = %g has norm %g; the IMU takes a unit "
                     "quaternion and normalises one only within %g of norm 1",
                  q[0], q[1], q[2], q[3], t, norm, QUATERNION_TOLERANCE);
        return STATUS_ERROR;
    }
    inertial_end = end_of_step(m, &d->inertial, R(sample_rate), "sample_rate", t, h);
    magnetic_end = end_of_step(m, &d->magnetic, R(mag_sample_rate), "mag_sample_rate", t, h);
    int n;
    if (inertial_end < 0 || magnetic_end < 0) return STATUS_ERROR;
    for (; d->inertial.next < inertial_end; d->inertial.next++) {
        /* the sample at t is already current unless inputs changed since it was read */
        if (!(d->inertial.current == d->inertial.next && !m->outputs_stale)) take_inertial(m, d, d->inertial.next);
        commit_inertial(m, d, d->inertial.next);
    }
    for (; d->magnetic.next < magnetic_end; d->magnetic.next++)
        if (!(d->magnetic.current == d->magnetic.next && !m->outputs_stale)) take_magnetic(m, d, d->magnetic.next);
    for (n = 0; n < N_MOTORS; n++) d->phase[n] = fmod(d->phase[n] + (RV(omega_r))[n] * h, 2.0 * PI);
    return STATUS_OK;
}

/* At an instant of `rate` not yet final, the sample follows the present inputs. */
static int due(ModelInstance *m, const Clock *c, double rate, int64_t *k) {
    double position = m->time * rate;
    *k = (int64_t)floor(position + SAMPLE_INSTANT_TOLERANCE);
    return *k == c->next && fabs(position - (double)*k) < SAMPLE_INSTANT_TOLERANCE;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    int64_t k;
    if (due(m, &d->inertial, R(sample_rate), &k)) take_inertial(m, d, k);
    if (due(m, &d->magnetic, R(mag_sample_rate), &k)) take_magnetic(m, d, k);
}
