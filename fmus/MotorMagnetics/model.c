/* MotorMagnetics: four brushless motors in the DC-motor approximation, their ESCs, a LiPo
 * battery, and the magnetic field of the motor currents at the magnetometer.
 *
 *   L di_n = c_n u - R i_n - k_e omega_n           c_n saturated to [0, 1]
 *   J_r domega_n = k_e i_n - k_m omega_n |omega_n|
 *   u = E(soc) - R_b i_batt,  i_batt = sum c_n max(i_n, 0)
 *   dsoc = -i_batt / capacity
 *   b_d = sum kappa_n i_n v_n
 *
 * The battery current is the ESC's average input current c_n i_n (PWM power balance); an ESC
 * never pushes current back into the battery, hence max(i_n, 0).
 *
 * The electrical time constant L/R (0.4 ms) is far below the mechanical one (about 25 ms), so
 * the currents are stiff. Each motor's linear part, y = (omega, i) with
 *   dy = A y + N(y),  A = [0, k_e/J_r; -k_e/L, -R/L],  N = (-k_m omega|omega|/J_r, c u/L),
 * is integrated by the exponential time-differencing RK4 of Cox and Matthews (J. Comput. Phys.
 * 176, 2002): exp(hA) and the phi-functions of hA are exact (2x2, by Lagrange interpolation
 * on the eigenvalues of A), and the slow remainder N gets RK4-like weights. Putting the
 * back-EMF and torque coupling in A keeps the fast current transient out of N, which would
 * otherwise reduce the order of the method. The state of charge uses classical RK4.
 */
#include <complex.h>
#include <math.h>

#include "airframe.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])

enum { OMEGA = 0, CURRENT = N_MOTORS, SOC = 2 * N_MOTORS };

typedef struct {
    double x[N_STATES];
    double v[N_MOTORS][3]; /* unit field directions */
    double step;           /* sub-step the matrices below were computed for */
    /* 2x2 row-major functions of h A: exp(hA), exp(hA/2), (h/2) phi1(hA/2), and the
     * ETDRK4 weights h(phi1 - 3 phi2 + 4 phi3), h(phi2 - 2 phi3), h(-phi2 + 4 phi3) */
    double e[4], e2[4], q[4], f1[4], f2[4], f3[4];
    int saturated[N_MOTORS];
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

static double clamp01(double c) { return c < 0.0 ? 0.0 : (c > 1.0 ? 1.0 : c); }

static double battery_current(ModelInstance *m, const double *x) {
    double total = 0.0;
    int n;
    for (n = 0; n < N_MOTORS; n++)
        if (x[CURRENT + n] > 0.0) total += clamp01((&R(c1))[n]) * x[CURRENT + n];
    return total;
}

static double battery_voltage(ModelInstance *m, const double *x) {
    double s = x[SOC];
    double cell = R(ocv0) + s * (R(ocv1) + s * (R(ocv2) + s * R(ocv3)));
    return R(n_cells) * cell - R(R_b) * battery_current(m, x);
}

/* The slow remainder N(x): drag and the command voltage for each motor, and dsoc. */
static void nonstiff(ModelInstance *m, const double *x, double *nx) {
    double u = battery_voltage(m, x);
    int n;
    for (n = 0; n < N_MOTORS; n++) {
        double w = x[OMEGA + n];
        nx[OMEGA + n] = -R(k_m) * w * fabs(w) / R(J_r);
        nx[CURRENT + n] = clamp01((&R(c1))[n]) * u / R(L_m);
    }
    nx[SOC] = -battery_current(m, x) / R(capacity);
}

/* phi_k(z) = sum_j z^j / (j + k)!; phi_k = 1/k! + z phi_(k+1). phi3 by its series near 0,
 * where the closed form cancels, and in closed form elsewhere. Index 0 is exp. */
static void phi0123(double complex z, double complex p[4]) {
    if (cabs(z) < 0.5) {
        double complex term = 1.0 / 6.0, sum = 0.0;
        int j;
        for (j = 0; j < 20; j++) {
            sum += term;
            term *= z / (j + 4);
        }
        p[3] = sum;
    } else {
        p[3] = (cexp(z) - 1.0 - z - 0.5 * z * z) / (z * z * z);
    }
    p[2] = 0.5 + z * p[3];
    p[1] = 1.0 + z * p[2];
    p[0] = 1.0 + z * p[1];
}

/* F(hA) = alpha I + beta A for a 2x2 A with eigenvalues l1 != l2, given F(h l1), F(h l2). */
static void interpolate(const double a[4], double complex l1, double complex l2, double complex f1,
                        double complex f2, double scale, double out[4]) {
    double complex beta = (f1 - f2) / (l1 - l2), alpha = (l1 * f2 - l2 * f1) / (l1 - l2);
    out[0] = scale * creal(alpha + beta * a[0]);
    out[1] = scale * creal(beta * a[1]);
    out[2] = scale * creal(beta * a[2]);
    out[3] = scale * creal(alpha + beta * a[3]);
}

static void etd_coefficients(ModelInstance *m, Data *d, double h) {
    const double a[4] = {0.0, R(k_e) / R(J_r), -R(k_e) / R(L_m), -R(R_m) / R(L_m)};
    double trace = a[0] + a[3], det = a[0] * a[3] - a[1] * a[2];
    double complex root = csqrt((double complex)(trace * trace - 4.0 * det));
    double complex l1 = 0.5 * (trace + root), l2 = 0.5 * (trace - root);
    double complex p1[4], p2[4], h1[4], h2[4], w1[3], w2[3];
    if (cabs(l1 - l2) < 1e-6 * cabs(l1)) { /* confluent: split by a negligible amount */
        l1 += 1e-5 * cabs(l1);
        l2 -= 1e-5 * cabs(l2);
    }
    phi0123(h * l1, p1);
    phi0123(h * l2, p2);
    phi0123(0.5 * h * l1, h1);
    phi0123(0.5 * h * l2, h2);
    interpolate(a, l1, l2, p1[0], p2[0], 1.0, d->e);
    interpolate(a, l1, l2, h1[0], h2[0], 1.0, d->e2);
    interpolate(a, l1, l2, h1[1], h2[1], 0.5 * h, d->q);
    w1[0] = p1[1] - 3.0 * p1[2] + 4.0 * p1[3];
    w2[0] = p2[1] - 3.0 * p2[2] + 4.0 * p2[3];
    w1[1] = p1[2] - 2.0 * p1[3];
    w2[1] = p2[2] - 2.0 * p2[3];
    w1[2] = -p1[2] + 4.0 * p1[3];
    w2[2] = -p2[2] + 4.0 * p2[3];
    interpolate(a, l1, l2, w1[0], w2[0], h, d->f1);
    interpolate(a, l1, l2, w1[1], w2[1], h, d->f2);
    interpolate(a, l1, l2, w1[2], w2[2], h, d->f3);
    d->step = h;
}

/* out = e y + q n on each motor's (omega, i) pair, with the 2x2 matrices e and q;
 * the state of charge gets e = 1 and q = h/2. */
static void stage(const double e[4], const double q[4], double h, const double *y, const double *n, double *out) {
    int k;
    for (k = 0; k < N_MOTORS; k++) {
        double w = y[OMEGA + k], i = y[CURRENT + k], nw = n[OMEGA + k], ni = n[CURRENT + k];
        out[OMEGA + k] = e[0] * w + e[1] * i + q[0] * nw + q[1] * ni;
        out[CURRENT + k] = e[2] * w + e[3] * i + q[2] * nw + q[3] * ni;
    }
    out[SOC] = y[SOC] + 0.5 * h * n[SOC];
}

static void etdrk4_step(ModelInstance *m, Data *d, double h) {
    double *x = d->x, nu[N_STATES], na[N_STATES], nb[N_STATES], nc[N_STATES];
    double a[N_STATES], b[N_STATES], c[N_STATES], tmp[N_STATES];
    int n, k;
    if (h != d->step) etd_coefficients(m, d, h);
    nonstiff(m, x, nu);
    stage(d->e2, d->q, h, x, nu, a);
    nonstiff(m, a, na);
    stage(d->e2, d->q, h, x, na, b);
    nonstiff(m, b, nb);
    for (k = 0; k < N_STATES; k++) tmp[k] = 2.0 * nb[k] - nu[k];
    stage(d->e2, d->q, h, a, tmp, c);
    nonstiff(m, c, nc);
    for (k = 0; k < N_STATES; k++) tmp[k] = na[k] + nb[k];
    for (n = 0; n < N_MOTORS; n++) {
        const double *e = d->e, *f1 = d->f1, *f2 = d->f2, *f3 = d->f3;
        double w = x[OMEGA + n], i = x[CURRENT + n];
        x[OMEGA + n] = e[0] * w + e[1] * i + f1[0] * nu[OMEGA + n] + f1[1] * nu[CURRENT + n] +
                       2.0 * (f2[0] * tmp[OMEGA + n] + f2[1] * tmp[CURRENT + n]) + f3[0] * nc[OMEGA + n] +
                       f3[1] * nc[CURRENT + n];
        x[CURRENT + n] = e[2] * w + e[3] * i + f1[2] * nu[OMEGA + n] + f1[3] * nu[CURRENT + n] +
                         2.0 * (f2[2] * tmp[OMEGA + n] + f2[3] * tmp[CURRENT + n]) + f3[2] * nc[OMEGA + n] +
                         f3[3] * nc[CURRENT + n];
    }
    x[SOC] += h / 6.0 * (nu[SOC] + 2.0 * tmp[SOC] + nc[SOC]);
}

fmi2Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const char *names[] = {"R_m", "L_m", "k_e", "J_r", "n_cells", "capacity", "sub_step"};
    const double values[] = {R(R_m), R(L_m), R(k_e), R(J_r), R(n_cells), R(capacity), R(sub_step)};
    unsigned i;
    int n;
    for (i = 0; i < sizeof values / sizeof values[0]; i++) {
        if (!(values[i] > 0.0) || !isfinite(values[i])) {
            log_error(m, "parameter %s = %g must be positive and finite", names[i], values[i]);
            return fmi2Error;
        }
    }
    if (!(R(k_m) >= 0.0) || !(R(R_b) >= 0.0) || !(R(soc0) >= 0.0 && R(soc0) <= 1.0)) {
        log_error(m, "k_m = %g and R_b = %g must be non-negative and soc0 = %g within [0, 1]",
                  R(k_m), R(R_b), R(soc0));
        return fmi2Error;
    }
    for (n = 0; n < N_MOTORS; n++) {
        const double *v = &R(v1_x) + 3 * n;
        double norm = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(norm > 0.0) || !isfinite(norm)) {
            log_error(m, "field direction of motor %d is zero or not finite; give v%d_x/y/z", n + 1,
                      n + 1);
            return fmi2Error;
        }
        for (i = 0; i < 3; i++) d->v[n][i] = v[i] / norm;
        d->x[OMEGA + n] = R(omega0);
        d->x[CURRENT + n] = R(k_m) * R(omega0) * fabs(R(omega0)) / R(k_e);
    }
    d->x[SOC] = R(soc0);
    d->step = -1.0;
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    int n = substep_count(m, h, R(sub_step), "sub_step"), k;
    (void)t;
    if (n == 0) return fmi2Error;
    for (k = 0; k < N_MOTORS; k++) {
        double c = (&R(c1))[k];
        int outside = c < 0.0 || c > 1.0;
        if (outside && !d->saturated[k])
            log_warning(m, "c%d = %g at t = %g is outside [0, 1]: saturated", k + 1, c, m->time);
        d->saturated[k] = outside;
    }
    for (k = 0; k < n; k++) etdrk4_step(m, d, h / n);
    return fmi2OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const double *x = d->x;
    int n, a;
    for (a = 0; a < 3; a++) (&R(b_d_x))[a] = 0.0;
    for (n = 0; n < N_MOTORS; n++) {
        double field = (&R(kappa1))[n] * x[CURRENT + n];
        (&R(omega_r1))[n] = x[OMEGA + n];
        (&R(domega_r1))[n] = (R(k_e) * x[CURRENT + n] - R(k_m) * x[OMEGA + n] * fabs(x[OMEGA + n])) / R(J_r);
        (&R(i1))[n] = x[CURRENT + n];
        for (a = 0; a < 3; a++) {
            (&R(b_d1_x))[3 * n + a] = field * d->v[n][a];
            (&R(b_d_x))[a] += field * d->v[n][a];
        }
    }
    R(i_batt) = battery_current(m, x);
    R(u_batt) = battery_voltage(m, x);
    R(soc) = x[SOC];
}
