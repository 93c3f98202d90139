/* Quadrotor: rigid body of a quad-X multirotor. NED inertial frame, FRD body frame.
 *
 *   dp = v
 *   m dv = m g e3 + R (-T e3 + F_d)                     thrust along -z_B
 *   F_d = -k_d sum|omega_n| (v_a,x, v_a,y, 0) - c_D,i |v_a| v_a,i - D v_a     v_a = R^T (v - wind)
 *   dq = 0.5 q (x) (0, omega) + k_norm (1 - |q|^2) q
 *   J domega = -omega x J omega + tau - omega x h_r + tau_r
 *
 * F_d: the rotor drag (H-force of blade flapping and induced drag, lumped at the centre of
 * mass as in RotorPy's multirotor) and optional parasitic drags (quadratic per body axis, and
 * linear isotropic D = drag), all on the airspeed.
 * Rotor n spins at -s_n omega_n e3 (airframe.h: s_n = +1 counter-clockwise seen from above),
 * so the rotors carry h_r = -J_r sum(s_n omega_n) e3. Their gyroscopic moment is -omega x h_r,
 * and spinning them up reacts on the body with -dh_r/dt = J_r sum(s_n domega_n) e3, which adds
 * to the drag torque k_m sum(s_n omega_n^2) e3 with the same sign.
 *
 * State x = (p[3], v[3], q[4], omega[3]); RK4 with sub-steps of at most sub_step.
 */
#include <math.h>

#include "airframe.h"
#include "quaternion.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])
#define RV(name) REAL_VECTOR(m, name)

/* Where each part of the state starts in x (p, v, q, omega); the table declares N_STATES. */
enum { POSITION = 0, VELOCITY = 3, ATTITUDE = 6, RATE = 10 };
typedef char state_layout_matches_the_table[(N_STATES == RATE + 3) ? 1 : -1];

typedef struct {
    double x[N_STATES];
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

/* Thrust and torques of the rotors at the present inputs. */
static void rotor_forces(ModelInstance *m, double *thrust, double tau[3]) {
    const double *w = RV(omega_r), *dw = RV(domega_r);
    int n;
    *thrust = 0.0;
    tau[0] = tau[1] = tau[2] = 0.0;
    for (n = 0; n < N_MOTORS; n++) {
        double w2 = w[n] * w[n];
        double t = R(k_f) * w2;
        *thrust += t;
        tau[0] -= R(arm) * ARM_Y[n] * t; /* r x (-t e3) = (-y t, x t, 0) */
        tau[1] += R(arm) * ARM_X[n] * t;
        tau[2] += SPIN[n] * (R(k_m) * w2 + R(J_r) * dw[n]);
    }
}

/* Drag force in {B} at velocity v (NED) and rotation r (body to NED, row-major). */
static void drag_force(ModelInstance *m, const double *v, const double r[9], double f[3]) {
    const double *w = RV(omega_r), *c = RV(c_D);
    double air[3], va[3], speed, rotor = 0.0;
    int i;
    for (i = 0; i < 3; i++) air[i] = v[i] - RV(wind)[i];
    for (i = 0; i < 3; i++) va[i] = r[i] * air[0] + r[3 + i] * air[1] + r[6 + i] * air[2];
    for (i = 0; i < N_MOTORS; i++) rotor += fabs(w[i]);
    speed = sqrt(va[0] * va[0] + va[1] * va[1] + va[2] * va[2]);
    for (i = 0; i < 3; i++) f[i] = -(c[i] * speed + R(drag)) * va[i] - (i < 2 ? R(k_d) * rotor * va[i] : 0.0);
}

/* Sum of s_n omega_n: the rotors' angular momentum is -J_r times this, along e3. */
static double spin_sum(ModelInstance *m) {
    double total = 0.0;
    int n;
    for (n = 0; n < N_MOTORS; n++) total += SPIN[n] * RV(omega_r)[n];
    return total;
}

static void derivatives(ModelInstance *m, double t, const double *x, double *dx) {
    const double *v = x + VELOCITY, *q = x + ATTITUDE, *w = x + RATE;
    double *dp = dx + POSITION, *dv = dx + VELOCITY, *dq = dx + ATTITUDE, *dw = dx + RATE;
    double thrust, tau[3], r[9], f[3], body[3], norm_error, gyro;
    (void)t;
    if (m->boolean[VB_clamped]) {
        int i;
        for (i = 0; i < N_STATES; i++) dx[i] = 0.0;
        return;
    }
    rotor_forces(m, &thrust, tau);
    rotation_from_quaternion(q, r);
    drag_force(m, v, r, f);
    body[0] = f[0] / R(m);
    body[1] = f[1] / R(m);
    body[2] = (f[2] - thrust) / R(m);
    dp[0] = v[0];
    dp[1] = v[1];
    dp[2] = v[2];
    dv[0] = r[0] * body[0] + r[1] * body[1] + r[2] * body[2];
    dv[1] = r[3] * body[0] + r[4] * body[1] + r[5] * body[2];
    dv[2] = R(g) + r[6] * body[0] + r[7] * body[1] + r[8] * body[2];
    norm_error = R(k_norm) * (1.0 - (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]));
    dq[0] = 0.5 * (-q[1] * w[0] - q[2] * w[1] - q[3] * w[2]) + norm_error * q[0];
    dq[1] = 0.5 * (q[0] * w[0] + q[2] * w[2] - q[3] * w[1]) + norm_error * q[1];
    dq[2] = 0.5 * (q[0] * w[1] + q[3] * w[0] - q[1] * w[2]) + norm_error * q[2];
    dq[3] = 0.5 * (q[0] * w[2] + q[1] * w[1] - q[2] * w[0]) + norm_error * q[3];
    gyro = R(J_r) * spin_sum(m); /* -omega x h_r = gyro (omega_y, -omega_x, 0) */
    dw[0] = (tau[0] + gyro * w[1] - (R(Jzz) - R(Jyy)) * w[1] * w[2]) / R(Jxx);
    dw[1] = (tau[1] - gyro * w[0] - (R(Jxx) - R(Jzz)) * w[2] * w[0]) / R(Jyy);
    dw[2] = (tau[2] - (R(Jyy) - R(Jxx)) * w[0] * w[1]) / R(Jzz);
}

Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    double c1, s1, c2, s2, c3, s3;
    const char *positive[] = {"m", "Jxx", "Jyy", "Jzz", "arm", "k_f", "g", "sub_step"};
    const double values[] = {R(m), R(Jxx), R(Jyy), R(Jzz), R(arm), R(k_f), R(g), R(sub_step)};
    const char *non_negative[] = {"k_m", "k_d", "c_Dx", "c_Dy", "c_Dz", "drag", "J_r", "k_norm"};
    const double others[] = {R(k_m), R(k_d), R(c_Dx), R(c_Dy), R(c_Dz), R(drag), R(J_r), R(k_norm)};
    unsigned i;
    for (i = 0; i < sizeof values / sizeof values[0]; i++) {
        if (!(values[i] > 0.0) || !isfinite(values[i])) {
            log_error(m, "parameter %s = %g must be positive and finite", positive[i], values[i]);
            return STATUS_ERROR;
        }
    }
    for (i = 0; i < sizeof others / sizeof others[0]; i++) {
        if (!(others[i] >= 0.0) || !isfinite(others[i])) {
            log_error(m, "parameter %s = %g must be non-negative and finite", non_negative[i], others[i]);
            return STATUS_ERROR;
        }
    }
    if (R(Jxx) + R(Jyy) < R(Jzz) || R(Jyy) + R(Jzz) < R(Jxx) || R(Jzz) + R(Jxx) < R(Jyy)) {
        log_error(m, "inertia (%g, %g, %g) violates the triangle inequality of a rigid body",
                  R(Jxx), R(Jyy), R(Jzz));
        return STATUS_ERROR;
    }
    d->x[POSITION] = R(p_x0);
    d->x[POSITION + 1] = R(p_y0);
    d->x[POSITION + 2] = R(p_z0);
    d->x[VELOCITY] = R(v_x0);
    d->x[VELOCITY + 1] = R(v_y0);
    d->x[VELOCITY + 2] = R(v_z0);
    /* Z-Y-X Euler angles to quaternion */
    c1 = cos(0.5 * R(theta1_0));
    s1 = sin(0.5 * R(theta1_0));
    c2 = cos(0.5 * R(theta2_0));
    s2 = sin(0.5 * R(theta2_0));
    c3 = cos(0.5 * R(theta3_0));
    s3 = sin(0.5 * R(theta3_0));
    d->x[ATTITUDE] = c3 * c2 * c1 + s3 * s2 * s1;
    d->x[ATTITUDE + 1] = c3 * c2 * s1 - s3 * s2 * c1;
    d->x[ATTITUDE + 2] = c3 * s2 * c1 + s3 * c2 * s1;
    d->x[ATTITUDE + 3] = s3 * c2 * c1 - c3 * s2 * s1;
    d->x[RATE] = R(omega_x0);
    d->x[RATE + 1] = R(omega_y0);
    d->x[RATE + 2] = R(omega_z0);
    if (m->boolean[VB_clamped]) {
        for (i = 0; i < 3; i++) d->x[VELOCITY + i] = d->x[RATE + i] = 0.0;
    }
    return STATUS_OK;
}

Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    int n = substep_count(m, h, R(sub_step), "sub_step"), k;
    double hh;
    if (n == 0) return STATUS_ERROR;
    hh = h / n;
    for (k = 0; k < n; k++) rk4_step(m, derivatives, t + k * hh, hh, d->x, N_STATES);
    return STATUS_OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const double *x = d->x;
    double dx[N_STATES], r[9], thrust, tau[3], f[3];
    int i;
    derivatives(m, m->time, x, dx);
    rotor_forces(m, &thrust, tau);
    rotation_from_quaternion(x + ATTITUDE, r);
    drag_force(m, x + VELOCITY, r, f);
    R(p_x) = x[POSITION];
    R(p_y) = x[POSITION + 1];
    R(p_z) = x[POSITION + 2];
    R(v_x) = x[VELOCITY];
    R(v_y) = x[VELOCITY + 1];
    R(v_z) = x[VELOCITY + 2];
    R(q0) = x[ATTITUDE];
    R(q1) = x[ATTITUDE + 1];
    R(q2) = x[ATTITUDE + 2];
    R(q3) = x[ATTITUDE + 3];
    R(omega_x) = x[RATE];
    R(omega_y) = x[RATE + 1];
    R(omega_z) = x[RATE + 2];
    /* f_B = R^T (dv - g e3) */
    for (i = 0; i < 3; i++)
        RV(f)[i] = r[i] * dx[VELOCITY] + r[3 + i] * dx[VELOCITY + 1] + r[6 + i] * (dx[VELOCITY + 2] - R(g));
    for (i = 0; i < LEN_R; i++) RV(R)[i] = r[i];
    R(theta1) = atan2(r[7], r[8]);
    R(theta2) = -asin(fmax(-1.0, fmin(1.0, r[6])));
    R(theta3) = atan2(r[3], r[0]);
    R(thrust) = thrust;
    R(tau_x) = tau[0];
    R(tau_y) = tau[1];
    R(tau_z) = tau[2];
    for (i = 0; i < 3; i++) RV(drag)[i] = m->boolean[VB_clamped] ? 0.0 : f[i];
}
