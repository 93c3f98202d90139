/* MotorMagnetics: four brushless motors in the DC-motor approximation, their ESCs, a LiPo
 * battery, and the magnetic field of the motor currents at the magnetometer (SPEC 3.2).
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
 * the currents are stiff. They are integrated by the exponential time-differencing RK4 of
 * Cox and Matthews (J. Comput. Phys. 176, 2002): the linear decay -R/L i is solved exactly
 * and the rest with RK4 weights, which reduces to classical RK4 on the other states.
 */
#include <math.h>

#include "airframe.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])

enum { W = 0, I = N_MOTORS, SOC = 2 * N_MOTORS };

typedef struct {
    double x[N_STATES];
    double v[N_MOTORS][3]; /* unit field directions */
    double step;           /* sub-step the coefficients below were computed for */
    double e, e2, q, f1, f2, f3;
    int saturated[N_MOTORS];
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

static double clamp01(double c) { return c < 0.0 ? 0.0 : (c > 1.0 ? 1.0 : c); }

static double battery_current(ModelInstance *m, const double *x) {
    double total = 0.0;
    int n;
    for (n = 0; n < N_MOTORS; n++)
        if (x[I + n] > 0.0) total += clamp01((&R(c1))[n]) * x[I + n];
    return total;
}

static double battery_voltage(ModelInstance *m, const double *x) {
    double s = x[SOC];
    double cell = R(ocv0) + s * (R(ocv1) + s * (R(ocv2) + s * R(ocv3)));
    return R(n_cells) * cell - R(R_b) * battery_current(m, x);
}

/* The non-stiff remainder N(x) = f(x) - lambda x, with lambda = -R/L on the currents. */
static void nonstiff(ModelInstance *m, const double *x, double *nx) {
    double u = battery_voltage(m, x);
    int n;
    for (n = 0; n < N_MOTORS; n++) {
        double w = x[W + n];
        nx[W + n] = (R(k_e) * x[I + n] - R(k_m) * w * fabs(w)) / R(J_r);
        nx[I + n] = (clamp01((&R(c1))[n]) * u - R(k_e) * w) / R(L_m);
    }
    nx[SOC] = -battery_current(m, x) / R(capacity);
}

/* phi_k(z) = sum_j z^j / (j + k)!; phi_k = 1/k! + z phi_(k+1). phi3 by its series near 0,
 * where the closed form cancels, and in closed form elsewhere. */
static void phi123(double z, double *p1, double *p2, double *p3) {
    if (fabs(z) < 0.5) {
        double term = 1.0 / 6.0, sum = 0.0;
        int j;
        for (j = 0; j < 20; j++) {
            sum += term;
            term *= z / (j + 4);
        }
        *p3 = sum;
    } else {
        *p3 = (exp(z) - 1.0 - z - 0.5 * z * z) / (z * z * z);
    }
    *p2 = 0.5 + z * *p3;
    *p1 = 1.0 + z * *p2;
}

static void etd_coefficients(ModelInstance *m, Data *d, double h) {
    double z = -R(R_m) / R(L_m) * h, p1, p2, p3, h1, dummy2, dummy3;
    phi123(z, &p1, &p2, &p3);
    phi123(0.5 * z, &h1, &dummy2, &dummy3);
    d->e = exp(z);
    d->e2 = exp(0.5 * z);
    d->q = 0.5 * h * h1;
    d->f1 = h * (p1 - 3.0 * p2 + 4.0 * p3);
    d->f2 = h * (p2 - 2.0 * p3);
    d->f3 = h * (-p2 + 4.0 * p3);
    d->step = h;
}

static void etdrk4_step(ModelInstance *m, Data *d, double h) {
    double *x = d->x, na[N_STATES], nb[N_STATES], nc[N_STATES], nu[N_STATES];
    double a[N_STATES], b[N_STATES], c[N_STATES];
    int k;
    if (h != d->step) etd_coefficients(m, d, h);
    nonstiff(m, x, nu);
    for (k = 0; k < N_STATES; k++) {
        int stiff = k >= I && k < SOC;
        a[k] = x[k] * (stiff ? d->e2 : 1.0) + (stiff ? d->q : 0.5 * h) * nu[k];
    }
    nonstiff(m, a, na);
    for (k = 0; k < N_STATES; k++) {
        int stiff = k >= I && k < SOC;
        b[k] = x[k] * (stiff ? d->e2 : 1.0) + (stiff ? d->q : 0.5 * h) * na[k];
    }
    nonstiff(m, b, nb);
    for (k = 0; k < N_STATES; k++) {
        int stiff = k >= I && k < SOC;
        c[k] = a[k] * (stiff ? d->e2 : 1.0) + (stiff ? d->q : 0.5 * h) * (2.0 * nb[k] - nu[k]);
    }
    nonstiff(m, c, nc);
    for (k = 0; k < N_STATES; k++) {
        if (k >= I && k < SOC)
            x[k] = d->e * x[k] + d->f1 * nu[k] + 2.0 * d->f2 * (na[k] + nb[k]) + d->f3 * nc[k];
        else
            x[k] += h / 6.0 * (nu[k] + 2.0 * (na[k] + nb[k]) + nc[k]);
    }
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
        d->x[W + n] = 0.0;
        d->x[I + n] = 0.0;
    }
    d->x[SOC] = R(soc0);
    d->step = -1.0;
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    int n = (int)ceil(h / R(sub_step) - 1e-9), k;
    (void)t;
    for (k = 0; k < N_MOTORS; k++) {
        double c = (&R(c1))[k];
        int outside = c < 0.0 || c > 1.0;
        if (outside && !d->saturated[k])
            log_warning(m, "c%d = %g at t = %g is outside [0, 1]: saturated", k + 1, c, m->time);
        d->saturated[k] = outside;
    }
    if (n < 1) n = 1;
    for (k = 0; k < n; k++) etdrk4_step(m, d, h / n);
    return fmi2OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const double *x = d->x;
    int n, a;
    for (a = 0; a < 3; a++) (&R(b_d_x))[a] = 0.0;
    for (n = 0; n < N_MOTORS; n++) {
        double field = (&R(kappa1))[n] * x[I + n];
        (&R(omega_r1))[n] = x[W + n];
        (&R(i1))[n] = x[I + n];
        for (a = 0; a < 3; a++) {
            (&R(b_d1_x))[3 * n + a] = field * d->v[n][a];
            (&R(b_d_x))[a] += field * d->v[n][a];
        }
    }
    R(i_batt) = battery_current(m, x);
    R(u_batt) = battery_voltage(m, x);
    R(soc) = x[SOC];
}
