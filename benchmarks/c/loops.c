/* Reference loops of the benchmark: the open loop and the closed loop of `tp` written by hand in
 * C, with the same FMI calls, the same explicit filter and controller and the same recording as
 * the orchestrator, so that the benchmark can say how far the orchestrator is from the floor and
 * check that both give the same trajectories, bit for bit.
 *
 * The explicit complementary filter (Mahony, Hamel, Pflimlin, "Nonlinear complementary filters
 * on the special orthogonal group", 2008) without the disturbance-aware corrections, and the
 * attitude, altitude and position-hold controller with its mixer, each in the order of
 * operations of the compiled Python code they stand for. Built by `quadcosim build` with the
 * system compiler; not part of the installed package. */
#include <math.h>
#include <stddef.h>
#include <string.h>
#include "rotation.h"

typedef int (*SetReal)(void *, const unsigned int *, size_t, const double *);
typedef int (*GetReal)(void *, const unsigned int *, size_t, double *);
typedef int (*DoStep)(void *, double, double, int);

typedef struct {
    SetReal set;
    GetReal get;
    DoStep step;
    void *component;
} Fmu;

typedef struct {
    const unsigned int *vr;
    size_t n;
} Refs;

typedef struct { /* the controller's parameters, by name (units in scenarios/flight/controller.py) */
    double mass, jx, jy, jz, gravity, thrust_coeff, max_rotor_thrust, resistance, ke, drag_torque_coeff,
        max_tilt, kp, kd, kp_yaw, kd_yaw, kp_z, kd_z, kp_xy, kd_xy, ki_xy;
    double mixer_inverse[4][4];
} Control;

typedef struct { /* the explicit filter's gains, references and initial state */
    double k1, k2, kP, kI;
    double gravity[3], field[3];
    double q0[4], b0[3];
} Explicit;

typedef struct {
    Fmu motors, body, imu;
    Refs motors_in, motors_out, body_rotors, body_wind, body_out, imu_rotors, imu_field, imu_motion, imu_out;
    const double *setpoint; /* one row per step */
    long setpoint_width;
    const double *wind; /* 3 */
    const double *field; /* 3: the field into the IMU when not the motors' (closed loop) */
    long steps;
    double dt;
    double *record; /* (steps + 1) rows of `width` */
    long width;
    const Control *control;  /* closed loop only */
    const Explicit *filter;  /* closed loop only */
    long failed_step; /* out */
    int failed_call;  /* out: FMI status, or -1 for a non-finite value */
} Loop;

enum { MOTORS_OUT = 34, BODY_OUT = 35, IMU_OUT = 24, ESTIMATOR_OUT = 16, CONTROLLER_OUT = 10 };
/* outputs of MotorMagnetics, Quadrotor and IMU used below (the FMUs' declaration order) */
enum { M_OMEGA_R = 0, M_B_D = 8, M_U_BATT = 11 };
enum { Q_Q = 0, Q_OMEGA = 4, Q_P = 10, Q_V = 13 };
enum { I_ACC = 0, I_GYRO = 3, I_MAG = 6 };
/* the setpoint's columns */
enum { S_ROLL, S_PITCH, S_YAW, S_X, S_Y, S_Z, S_HOLD };

static double max2(double a, double b) { return b > a ? b : a; }
static double min2(double a, double b) { return b < a ? b : a; }
static double clamp(double x, double lo, double hi) { return min2(max2(x, lo), hi); }

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* out = R^T v / |R^T v|, R row-major */
static void body_direction(const double r[3][3], double vx, double vy, double vz, double *out) {
    out[0] = r[0][0] * vx + r[1][0] * vy + r[2][0] * vz;
    out[1] = r[0][1] * vx + r[1][1] * vy + r[2][1] * vz;
    out[2] = r[0][2] * vx + r[1][2] * vy + r[2][2] * vz;
    double n = norm3(out);
    for (int i = 0; i < 3; i++)
        out[i] /= n;
}

static void add_cross(const double *v, double norm_v, const double *vhat, double gain, double *w) {
    double scale = gain / norm_v;
    w[0] += scale * (v[1] * vhat[2] - v[2] * vhat[1]);
    w[1] += scale * (v[2] * vhat[0] - v[0] * vhat[2]);
    w[2] += scale * (v[0] * vhat[1] - v[1] * vhat[0]);
}

/* one explicit-filter step: state q, b; writes q, theta, b, omega, weights */
static void explicit_filter(const Explicit *f, double *q, double *b, const double *imu, double dt, double *y) {
    const double *acc = imu + I_ACC, *gyro = imu + I_GYRO, *mag = imu + I_MAG;
    double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3], r[3][3], up[3], field[3], w[3] = {0.0, 0.0, 0.0};
    rotation_of_quaternion(q0, q1, q2, q3, r);
    body_direction(r, -f->gravity[0], -f->gravity[1], -f->gravity[2], up);
    body_direction(r, f->field[0], f->field[1], f->field[2], field);
    double acc_weight = norm3(acc) > 0.0 ? 1.0 : 0.0, mag_weight = norm3(mag) > 0.0 ? 1.0 : 0.0;
    if (acc_weight > 0.0)
        add_cross(acc, norm3(acc), up, f->k1 * acc_weight, w);
    if (mag_weight > 0.0)
        add_cross(mag, norm3(mag), field, f->k2 * mag_weight, w);
    for (int i = 0; i < 3; i++)
        b[i] -= dt * f->kI * w[i];
    /* exponential map of the corrected rate over dt */
    double wx = gyro[0] - b[0] + f->kP * w[0], wy = gyro[1] - b[1] + f->kP * w[1], wz = gyro[2] - b[2] + f->kP * w[2];
    double angle = sqrt(wx * wx + wy * wy + wz * wz) * dt, s = 0.5 * dt, c = 1.0;
    if (angle > 1e-12) {
        s = sin(0.5 * angle) / (angle / dt);
        c = cos(0.5 * angle);
    }
    double e1 = s * wx, e2 = s * wy, e3 = s * wz;
    q[0] = q0 * c - q1 * e1 - q2 * e2 - q3 * e3;
    q[1] = q0 * e1 + q1 * c + q2 * e3 - q3 * e2;
    q[2] = q0 * e2 - q1 * e3 + q2 * c + q3 * e1;
    q[3] = q0 * e3 + q1 * e2 - q2 * e1 + q3 * c;
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++)
        q[i] /= n;
    q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    for (int i = 0; i < 4; i++)
        y[i] = q[i];
    y[4] = atan2(2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2));
    y[5] = asin(min2(1.0, max2(-1.0, 2.0 * (q0 * q2 - q1 * q3))));
    y[6] = atan2(2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q2 * q2 + q3 * q3));
    for (int i = 0; i < 3; i++) {
        y[7 + i] = b[i];
        y[10 + i] = gyro[i] - b[i];
    }
    y[13] = acc_weight, y[14] = mag_weight, y[15] = 0.0;
}

/* one controller step: setpoint, ground truth (body outputs), battery voltage; state: the
 * position errors' integral */
static void controller(const Control *p, const double *sp, const double *body, double u_batt, double dt,
                       double *integral, double *y) {
    double roll_d = sp[S_ROLL], pitch_d = sp[S_PITCH], yaw = sp[S_YAW], g = p->gravity;
    if (sp[S_HOLD] > 0.5) {
        double ex = sp[S_X] - body[Q_P], ey = sp[S_Y] - body[Q_P + 1];
        if (p->ki_xy > 0.0) {
            double limit = g * tan(p->max_tilt) / p->ki_xy;
            integral[0] = clamp(integral[0] + ex * dt, -limit, limit);
            integral[1] = clamp(integral[1] + ey * dt, -limit, limit);
        }
        double ax = p->kp_xy * ex + p->ki_xy * integral[0] - p->kd_xy * body[Q_V];
        double ay = p->kp_xy * ey + p->ki_xy * integral[1] - p->kd_xy * body[Q_V + 1];
        double forward = cos(yaw) * ax + sin(yaw) * ay, right = -sin(yaw) * ax + cos(yaw) * ay;
        roll_d = clamp(atan(right / g), -p->max_tilt, p->max_tilt);
        pitch_d = clamp(-atan(forward / g), -p->max_tilt, p->max_tilt);
    }
    double c1 = cos(0.5 * roll_d), s1 = sin(0.5 * roll_d), c2 = cos(0.5 * pitch_d), s2 = sin(0.5 * pitch_d);
    double c3 = cos(0.5 * yaw), s3 = sin(0.5 * yaw);
    double d0 = c3 * c2 * c1 + s3 * s2 * s1, d1 = c3 * c2 * s1 - s3 * s2 * c1;
    double d2 = c3 * s2 * c1 + s3 * c2 * s1, d3 = s3 * c2 * c1 - c3 * s2 * s1;
    const double *q = body + Q_Q, *omega = body + Q_OMEGA;
    double e0 = d0 * q[0] + d1 * q[1] + d2 * q[2] + d3 * q[3];
    double e1 = d0 * q[1] - d1 * q[0] - d2 * q[3] + d3 * q[2];
    double e2 = d0 * q[2] + d1 * q[3] - d2 * q[0] - d3 * q[1];
    double e3 = d0 * q[3] - d1 * q[2] + d2 * q[1] - d3 * q[0];
    double sign = e0 >= 0.0 ? 2.0 : -2.0, wx = omega[0], wy = omega[1], wz = omega[2];
    double tx = p->jx * (-p->kp * sign * e1 - p->kd * wx) + (p->jz - p->jy) * wy * wz;
    double ty = p->jy * (-p->kp * sign * e2 - p->kd * wy) + (p->jx - p->jz) * wz * wx;
    double tz = p->jz * (-p->kp_yaw * sign * e3 - p->kd_yaw * wz) + (p->jy - p->jx) * wx * wy;
    double r33 = max2(1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]), 0.5);
    double a_z = p->kp_z * (sp[S_Z] - body[Q_P + 2]) - p->kd_z * body[Q_V + 2];
    double thrust = p->mass * (g - a_z) / r33;
    u_batt = max2(u_batt, 1.0);
    for (int n = 0; n < 4; n++) {
        const double *m = p->mixer_inverse[n];
        double t_n = clamp(m[0] * thrust + m[1] * tx + m[2] * ty + m[3] * tz, 0.0, p->max_rotor_thrust);
        double omega_n = sqrt(t_n / p->thrust_coeff);
        double current = p->drag_torque_coeff * omega_n * fabs(omega_n) / p->ke;
        y[n] = clamp((p->resistance * current + p->ke * omega_n) / u_batt, 0.0, 1.0);
    }
    y[4] = thrust, y[5] = tx, y[6] = ty, y[7] = tz, y[8] = roll_d, y[9] = pitch_d;
}

static int finite(const double *row, long n) {
    for (long i = 0; i < n; i++)
        if (!isfinite(row[i]))
            return 0;
    return 1;
}

#define CALL(expression)                                                                                         \
    do {                                                                                                         \
        int status_ = (expression);                                                                              \
        if (status_ > 1) {                                                                                       \
            p->failed_step = n, p->failed_call = status_;                                                        \
            return status_;                                                                                      \
        }                                                                                                        \
    } while (0)

/* the plant's outputs at step n; `field` is the IMU's magnetic disturbance */
static int plant_outputs(Loop *p, long n, double *m, double *b, double *i, const double *field) {
    CALL(p->motors.get(p->motors.component, p->motors_out.vr, p->motors_out.n, m));
    CALL(p->body.set(p->body.component, p->body_rotors.vr, p->body_rotors.n, m + M_OMEGA_R));
    CALL(p->body.set(p->body.component, p->body_wind.vr, p->body_wind.n, p->wind));
    CALL(p->body.get(p->body.component, p->body_out.vr, p->body_out.n, b));
    CALL(p->imu.set(p->imu.component, p->imu_rotors.vr, p->imu_rotors.n, m + M_OMEGA_R));
    CALL(p->imu.set(p->imu.component, p->imu_motion.vr, p->imu_motion.n, b + Q_Q));
    CALL(p->imu.set(p->imu.component, p->imu_field.vr, p->imu_field.n, field));
    CALL(p->imu.get(p->imu.component, p->imu_out.vr, p->imu_out.n, i));
    return 0;
}

static int plant_step(Loop *p, long n, double t) {
    CALL(p->motors.step(p->motors.component, t, p->dt, 1));
    CALL(p->body.step(p->body.component, t, p->dt, 1));
    CALL(p->imu.step(p->imu.component, t, p->dt, 1));
    return 0;
}

/* Record row: setpoint, MotorMagnetics, Quadrotor, IMU outputs. Returns 0, an FMI status, or -1
 * for a non-finite value (failed_step says where). */
__attribute__((visibility("default"))) int open_loop(Loop *p) {
    double m[MOTORS_OUT], b[BODY_OUT], i[IMU_OUT];
    long w = p->setpoint_width;
    for (long n = 0; n <= p->steps; n++) {
        double t = (double)n * p->dt, *row = p->record + n * p->width;
        const double *sp = p->setpoint + n * w;
        CALL(p->motors.set(p->motors.component, p->motors_in.vr, p->motors_in.n, sp));
        if (plant_outputs(p, n, m, b, i, m + M_B_D))
            return p->failed_call;
        memcpy(row, sp, w * sizeof(double));
        memcpy(row + w, m, sizeof m);
        memcpy(row + w + MOTORS_OUT, b, sizeof b);
        memcpy(row + w + MOTORS_OUT + BODY_OUT, i, sizeof i);
        if (!finite(row, p->width)) {
            p->failed_step = n, p->failed_call = -1;
            return -1;
        }
        if (n < p->steps && plant_step(p, n, t))
            return p->failed_call;
    }
    return 0;
}

/* Record row: setpoint, MotorMagnetics, Quadrotor, IMU, estimator, controller outputs; the
 * controller fed by the ground truth, the estimator alongside. */
__attribute__((visibility("default"))) int closed_loop(Loop *p) {
    double m[MOTORS_OUT], b[BODY_OUT], i[IMU_OUT], e[ESTIMATOR_OUT], c[CONTROLLER_OUT];
    double q[4], bias[3], integral[2] = {0.0, 0.0};
    long w = p->setpoint_width;
    memcpy(q, p->filter->q0, sizeof q);
    memcpy(bias, p->filter->b0, sizeof bias);
    for (long n = 0; n <= p->steps; n++) {
        double t = (double)n * p->dt, *row = p->record + n * p->width;
        const double *sp = p->setpoint + n * w;
        if (plant_outputs(p, n, m, b, i, p->field))
            return p->failed_call;
        explicit_filter(p->filter, q, bias, i, p->dt, e);
        controller(p->control, sp, b, m[M_U_BATT], p->dt, integral, c);
        memcpy(row, sp, w * sizeof(double));
        memcpy(row + w, m, sizeof m);
        memcpy(row + w + MOTORS_OUT, b, sizeof b);
        memcpy(row + w + MOTORS_OUT + BODY_OUT, i, sizeof i);
        memcpy(row + w + MOTORS_OUT + BODY_OUT + IMU_OUT, e, sizeof e);
        memcpy(row + w + MOTORS_OUT + BODY_OUT + IMU_OUT + ESTIMATOR_OUT, c, sizeof c);
        if (!finite(row, p->width)) {
            p->failed_step = n, p->failed_call = -1;
            return -1;
        }
        if (n < p->steps) {
            CALL(p->motors.set(p->motors.component, p->motors_in.vr, p->motors_in.n, c));
            if (plant_step(p, n, t))
                return p->failed_call;
        }
    }
    return 0;
}
