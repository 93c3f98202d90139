/* C reference of the batch explicit filter, for the benchmark of the compiled batch path.
 *
 * The same update as estimators/core.py's `update` with kind EXPLICIT (the weights of the
 * disturbance-aware corrections, heading-only magnetometer, rest detector, bias update, then
 * the exponential-map or Euler quaternion step and the Euler angles), written operation for
 * operation in the same order, so that the estimates agree to the last bit when both are
 * compiled without floating-point contraction (-ffp-contract=off; numba contracts nothing
 * without fastmath). The attitude starts from q0 (no TRIAD start).
 *
 * The slots of the layouts are numbered as in estimators/layout.py; the benchmark checks
 * `batch_explicit_slots` against those layouts before any run.
 */
#include <math.h>
#include <stddef.h>
#include "rotation.h"

/* input sample */
enum { ACC = 0, GYRO = 3, MAG = 6, INPUT_SIZE = 18 };
/* configuration */
enum { GRAVITY = 0, FIELD = 3, DISCRETE = 6 };
/* gain vector */
enum { K1 = 0, K2 = 1, KP = 3, KI = 4, HEADING_ONLY = 5, ACC_TOL = 6, MAG_NORM_TOL = 7, MAG_DIP_TOL = 8,
       REST_GYRO = 9, REST_ACC = 10, REST_MIN_TIME = 11, REST_GAIN = 12, GAIN_SIZE = 26 };
enum { EULER = 1 };
#define REST_LOWPASS_TAU 0.5 /* s, as estimators/layout.py */

/* Writes the slot numbers this file uses, in the order the benchmark lists them. */
void batch_explicit_slots(long *slots) {
    const long used[] = {ACC, GYRO, MAG, INPUT_SIZE, GRAVITY, FIELD, DISCRETE, K1, K2, KP, KI, HEADING_ONLY,
                         ACC_TOL, MAG_NORM_TOL, MAG_DIP_TOL, REST_GYRO, REST_ACC, REST_MIN_TIME, REST_GAIN,
                         GAIN_SIZE, EULER};
    for (size_t i = 0; i < sizeof used / sizeof used[0]; i++) slots[i] = used[i];
}

typedef struct {
    double q[4], b[3], theta[3], gyro_lp[3], acc_lp[3], rest_time;
    int started;
} State;

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

static double ramp(double deviation, double tolerance) {
    if (tolerance <= 0.0) return 1.0;
    double w = 1.0 - fabs(deviation) / tolerance;
    return w > 0.0 ? w : 0.0;
}

static double clamp1(double s) {
    double low = s > -1.0 ? s : -1.0;
    return low < 1.0 ? low : 1.0;
}

/* out = R(q)^T v / |.| */
static void body(const double r[3][3], double vx, double vy, double vz, double *out) {
    out[0] = r[0][0] * vx + r[1][0] * vy + r[2][0] * vz;
    out[1] = r[0][1] * vx + r[1][1] * vy + r[2][1] * vz;
    out[2] = r[0][2] * vx + r[1][2] * vy + r[2][2] * vz;
    double n = norm3(out);
    for (int i = 0; i < 3; i++) out[i] /= n;
}

/* w += gain (v/|v|) x vhat */
static void add_cross(const double *v, double norm_v, const double *vhat, double gain, double *w) {
    double scale = gain / norm_v;
    w[0] += scale * (v[1] * vhat[2] - v[2] * vhat[1]);
    w[1] += scale * (v[2] * vhat[0] - v[0] * vhat[2]);
    w[2] += scale * (v[0] * vhat[1] - v[1] * vhat[0]);
}

static int at_rest(State *x, const double *acc, const double *gyro, const double *gains, double g, double dt) {
    double alpha = dt / (REST_LOWPASS_TAU + dt);
    if (!x->started) {
        x->started = 1;
        for (int i = 0; i < 3; i++) x->gyro_lp[i] = gyro[i], x->acc_lp[i] = acc[i];
    }
    for (int i = 0; i < 3; i++) {
        x->gyro_lp[i] += alpha * (gyro[i] - x->gyro_lp[i]);
        x->acc_lp[i] += alpha * (acc[i] - x->acc_lp[i]);
    }
    if (gains[REST_GYRO] <= 0.0) return 0;
    int still = norm3(x->gyro_lp) < gains[REST_GYRO] && fabs(norm3(x->acc_lp) - g) < gains[REST_ACC];
    x->rest_time = still ? x->rest_time + dt : 0.0;
    return x->rest_time >= gains[REST_MIN_TIME];
}

static void integrate(double *q, double wx, double wy, double wz, double dt, int discretisation) {
    if (discretisation == EULER) {
        double d0 = 0.5 * (-q[1] * wx - q[2] * wy - q[3] * wz);
        double d1 = 0.5 * (q[0] * wx + q[2] * wz - q[3] * wy);
        double d2 = 0.5 * (q[0] * wy + q[3] * wx - q[1] * wz);
        double d3 = 0.5 * (q[0] * wz + q[1] * wy - q[2] * wx);
        q[0] += dt * d0;
        q[1] += dt * d1;
        q[2] += dt * d2;
        q[3] += dt * d3;
    } else {
        double angle = sqrt(wx * wx + wy * wy + wz * wz) * dt, s, c;
        if (angle > 1e-12) {
            s = sin(0.5 * angle) / (angle / dt);
            c = cos(0.5 * angle);
        } else {
            s = 0.5 * dt;
            c = 1.0;
        }
        double e1 = s * wx, e2 = s * wy, e3 = s * wz;
        double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
        q[0] = q0 * c - q1 * e1 - q2 * e2 - q3 * e3;
        q[1] = q0 * e1 + q1 * c + q2 * e3 - q3 * e2;
        q[2] = q0 * e2 - q1 * e3 + q2 * c + q3 * e1;
        q[3] = q0 * e3 + q1 * e2 - q2 * e1 + q3 * c;
    }
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++) q[i] /= n;
}

static void update(State *x, const double *u, const double *gains, const double *config, double dt) {
    const double *acc = u + ACC, *gyro = u + GYRO, *mag = u + MAG;
    double *q = x->q, *b = x->b;
    double r[3][3], v_up[3], v_field[3], w[3] = {0.0, 0.0, 0.0};
    double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    rotation_of_quaternion(q0, q1, q2, q3, r);
    double gx = config[GRAVITY], gy = config[GRAVITY + 1], gz = config[GRAVITY + 2];
    double mx = config[FIELD], my = config[FIELD + 1], mz = config[FIELD + 2];
    double g = sqrt(gx * gx + gy * gy + gz * gz);
    body(r, -gx, -gy, -gz, v_up);
    body(r, mx, my, mz, v_field);
    /* weights of the corrections */
    double field = sqrt(mx * mx + my * my + mz * mz), na = norm3(acc), nm = norm3(mag);
    double acc_weight = na > 0.0 ? ramp(na - g, gains[ACC_TOL]) : 0.0;
    double mag_weight = nm > 0.0 ? ramp(nm / field - 1.0, gains[MAG_NORM_TOL]) : 0.0;
    if (nm > 0.0 && gains[MAG_DIP_TOL] > 0.0) {
        double sin_dip = -(mag[0] * v_up[0] + mag[1] * v_up[1] + mag[2] * v_up[2]) / nm;
        double sin_ref = -(v_field[0] * v_up[0] + v_field[1] * v_up[1] + v_field[2] * v_up[2]);
        mag_weight *= ramp(asin(clamp1(sin_dip)) - asin(clamp1(sin_ref)), gains[MAG_DIP_TOL]);
    }
    /* explicit correction */
    if (acc_weight > 0.0) add_cross(acc, norm3(acc), v_up, gains[K1] * acc_weight, w);
    if (mag_weight > 0.0) {
        if (gains[HEADING_ONLY] > 0.0) {
            double m[3] = {0.0, 0.0, 0.0};
            add_cross(mag, norm3(mag), v_field, gains[K2] * mag_weight, m);
            double along = m[0] * v_up[0] + m[1] * v_up[1] + m[2] * v_up[2];
            for (int i = 0; i < 3; i++) m[i] = 0.0 * (m[i] - along * v_up[i]) + 1.0 * along * v_up[i];
            for (int i = 0; i < 3; i++) w[i] += m[i];
        } else {
            add_cross(mag, norm3(mag), v_field, gains[K2] * mag_weight, w);
        }
    }
    int rest = at_rest(x, acc, gyro, gains, g, dt);
    for (int i = 0; i < 3; i++) {
        b[i] -= dt * gains[KI] * w[i];
        if (rest) b[i] += dt * gains[REST_GAIN] * (gyro[i] - b[i]);
    }
    double kp = gains[KP];
    integrate(q, gyro[0] - b[0] + kp * w[0], gyro[1] - b[1] + kp * w[1], gyro[2] - b[2] + kp * w[2], dt,
              (int)config[DISCRETE]);
    /* Z-Y-X Euler angles, part of the filter's state */
    q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    x->theta[0] = atan2(2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2));
    x->theta[1] = asin(clamp1(2.0 * (q0 * q2 - q1 * q3)));
    x->theta[2] = atan2(2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q2 * q2 + q3 * q3));
}

/* Runs gain_sets filters over `samples` samples (rows of INPUT_SIZE doubles), one after the
 * other, single-threaded; writes the attitude of every sample into q_out (gain_sets, samples, 4). */
void batch_explicit(long gain_sets, long samples, const double *inputs, const double *gains, const double *config,
                    double dt, const double *q0, const double *b0, double *q_out) {
    for (long k = 0; k < gain_sets; k++) {
        State x = {{q0[0], q0[1], q0[2], q0[3]}, {b0[0], b0[1], b0[2]}, {0}, {0}, {0}, 0.0, 0};
        const double *gain = gains + k * GAIN_SIZE;
        double *out = q_out + k * samples * 4;
        for (long n = 0; n < samples; n++) {
            update(&x, inputs + n * INPUT_SIZE, gain, config, dt);
            for (int i = 0; i < 4; i++) out[4 * n + i] = x.q[i];
        }
    }
}
