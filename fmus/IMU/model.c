/* IMU: accelerometer, gyrometer and magnetometer sampled at sample_rate and held.
 *
 *   acc = f_B + b_a + n_a
 *   gyro = omega + b_g + n_g
 *   magneto = A R^T m_I + b_s + b_d + n_m         (Metge et al. 2013, eq. 1)
 *   R_reel = R(q)
 *
 * The sample at t_k = k / sample_rate uses the inputs at t_k: while the time is t_k it follows
 * the inputs as they are set, and it is final once a step leaves t_k. Instants inside a step
 * see the inputs held over the step.
 * Noise sample k of channel c is a pure function of (seed, k, c), so streams do not depend
 * on the co-simulation step; its standard deviation is density * sqrt(sample_rate).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "quaternion.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])
#define RV(name) REAL_VECTOR(m, name)

enum { CH_ACC = 0, CH_GYRO = 3, CH_MAG = 6, CH_WALK_GYRO = 9, CH_WALK_ACC = 12 };

typedef struct {
    int64_t next_sample; /* first instant not yet final */
    int64_t current;     /* instant of the sample the outputs hold */
    double gyro_bias[3], acc_bias[3];
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

static uint64_t splitmix64(uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Standard normal draw number `channel` of sample `k` (Box-Muller on two hashed uniforms). */
static double gaussian(int seed, int64_t k, int channel) {
    uint64_t key = splitmix64((uint64_t)(uint32_t)seed) ^ ((uint64_t)k * 64u + 2u * (uint64_t)channel);
    double u1 = ((double)(splitmix64(key) >> 11) + 1.0) * 0x1.0p-53; /* (0, 1] */
    double u2 = (double)(splitmix64(key ^ 0xD1B54A32D192ED03ull) >> 11) * 0x1.0p-53;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

static void take_sample(ModelInstance *m, Data *d, int64_t k) {
    d->current = k;
    const double *q = RV(q), *w = RV(omega), *f = RV(f), *bd = RV(b_d);
    const double *a = RV(A), *bs = RV(b_s), *mi = RV(m_I);
    double r[9], body[3], sd_acc = 0.0, sd_gyro = 0.0, sd_mag = 0.0, noise[CH_WALK_GYRO];
    int noisy = m->boolean[VB_noise_enabled], biased = m->boolean[VB_bias_enabled], i, c;
    rotation_from_quaternion(q, r);
    if (noisy) {
        double root_rate = sqrt(R(sample_rate));
        sd_acc = R(acc_noise_density) * root_rate;
        sd_gyro = R(gyro_noise_density) * root_rate;
        sd_mag = R(mag_noise_density) * root_rate;
    }
    for (c = 0; c < CH_WALK_GYRO; c++) noise[c] = noisy ? gaussian(m->integer[VI_seed], k, c) : 0.0;
    for (i = 0; i < 3; i++) body[i] = r[i] * mi[0] + r[3 + i] * mi[1] + r[6 + i] * mi[2]; /* R^T m_I */
    for (i = 0; i < 3; i++) {
        RV(acc)[i] = f[i] + (biased ? d->acc_bias[i] : 0.0) + sd_acc * noise[CH_ACC + i];
        RV(gyro)[i] = w[i] + (biased ? d->gyro_bias[i] : 0.0) + sd_gyro * noise[CH_GYRO + i];
        RV(magneto)[i] = a[3 * i] * body[0] + a[3 * i + 1] * body[1] + a[3 * i + 2] * body[2] + bs[i] +
                             bd[i] + sd_mag * noise[CH_MAG + i];
        RV(gyro_bias)[i] = biased ? d->gyro_bias[i] : 0.0;
        RV(acc_bias)[i] = biased ? d->acc_bias[i] : 0.0;
    }
    for (i = 0; i < LEN_R_reel; i++) RV(R_reel)[i] = r[i];
}

/* Sample k is final: the biases walk on to sample k + 1. */
static void commit_sample(ModelInstance *m, Data *d, int64_t k) {
    double root_dt = sqrt(1.0 / R(sample_rate));
    int seed = m->integer[VI_seed], i;
    if (R(gyro_bias_walk) == 0.0 && R(acc_bias_walk) == 0.0) return;
    for (i = 0; i < 3; i++) {
        d->gyro_bias[i] += R(gyro_bias_walk) * root_dt * gaussian(seed, k, CH_WALK_GYRO + i);
        d->acc_bias[i] += R(acc_bias_walk) * root_dt * gaussian(seed, k, CH_WALK_ACC + i);
    }
}


fmi2Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    int i;
    if (!(R(sample_rate) > 0.0) || !isfinite(R(sample_rate))) {
        log_error(m, "parameter sample_rate = %g Hz must be positive and finite", R(sample_rate));
        return fmi2Error;
    }
    if (!(R(gyro_noise_density) >= 0.0) || !(R(acc_noise_density) >= 0.0) ||
        !(R(mag_noise_density) >= 0.0) || !(R(gyro_bias_walk) >= 0.0) || !(R(acc_bias_walk) >= 0.0)) {
        log_error(m, "noise densities and bias walks must be non-negative");
        return fmi2Error;
    }
    for (i = 0; i < 3; i++) {
        d->gyro_bias[i] = RV(b_g)[i];
        d->acc_bias[i] = RV(b_a)[i];
    }
    d->next_sample = (int64_t)ceil(m->time * R(sample_rate) - 1e-6);
    d->current = -1;
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    /* instants in [t, t + h) become final, with the inputs held over the step */
    double last = ceil((t + h) * R(sample_rate) - 1e-6);
    int64_t end;
    char what[64];
    snprintf(what, sizeof what, "samples at sample_rate = %g Hz", R(sample_rate));
    if (!work_allowed(m, last - (double)d->next_sample, h, what,
                      "take shorter communication steps or a lower sample_rate"))
        return fmi2Error;
    end = (int64_t)last;
    for (; d->next_sample < end; d->next_sample++) {
        /* the sample at t is already current unless inputs changed since it was read */
        if (!(d->current == d->next_sample && !m->outputs_stale)) take_sample(m, d, d->next_sample);
        commit_sample(m, d, d->next_sample);
    }
    return fmi2OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    double position = m->time * R(sample_rate);
    int64_t k = (int64_t)floor(position + 1e-6);
    /* at a sample instant not yet final, the sample follows the present inputs */
    if (k == d->next_sample && fabs(position - (double)k) < 1e-6) take_sample(m, d, k);
}
