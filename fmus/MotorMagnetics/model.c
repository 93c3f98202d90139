/* MotorMagnetics: four brushless motors in the DC-motor approximation, their ESCs, a LiPo
 * battery, and the magnetic field the ESCs' supply cables make at the magnetometer.
 *
 *   L di_n = c_n u - R i_n - k_e omega_n           c_n saturated to [0, 1]
 *   J_r domega_n = k_e i_n - k_m omega_n |omega_n|
 *   i_s,n = c_n i_n                                 ESC input (supply) current, averaged PWM model
 *   u = E(soc) - R_b i_batt,  i_batt = sum i_s,n,  dsoc = -i_batt / capacity
 *   b_d = sum kappa_n i_s,n v_n                     field of the supply cables
 *
 * ESC behaviour when the back-EMF exceeds its output (c_n u < k_e omega_n):
 * - free-wheeling (regenerative = false, the default): the motor current decays through the
 *   free-wheeling diodes and stops at zero; the ESC's output then floats and the rotor coasts
 *   (i_n = 0) until c_n u exceeds k_e omega_n again. Motor and supply currents stay >= 0.
 * - regenerative braking (regenerative = true, complementary PWM): the current reverses, brakes
 *   the rotor and flows back into the battery (i_s,n < 0).
 * Current limit: |i_n| <= i_max; at the limit the ESC holds the current there (i_n = i_max)
 * until the motor's own dynamics would take it below.
 *
 * Integration. Each conducting motor's linear part, y = (omega, i) with
 *   dy = A y + N(y),  A = [0, k_e/J_r; -k_e/L, -R/L],  N = (-k_m omega|omega|/J_r, c u/L),
 * is integrated by the exponential time-differencing RK4 of Cox and Matthews ("Exponential
 * time differencing for stiff systems", J. Comput. Phys. 176, 2002): exp(hA) and the
 * phi-functions of hA are exact (2x2, by Lagrange interpolation on the eigenvalues of A), and
 * the slow remainder N gets RK4-like weights. A motor held at a current bound has A = 0 and
 * N = ((k_e i - k_m omega|omega|)/J_r, 0), for which the same formulas are classical RK4.
 * The bounds make the right-hand side switch; integrating across a switch would cost the
 * method its order (a current falling at 25 kA/s overshoots zero by amperes within a
 * sub-step). So a sub-step that would cross a bound is cut at the crossing, located to 1e-12
 * of the sub-step by the Illinois method on the step length, and resumed in the new mode.
 * The state of charge uses classical RK4.
 * A battery run empty (state of charge below 0) fails the step with an error saying when: the
 * flight cannot go on, and the charge never leaves its physical range.
 */
#include <complex.h>
#include <math.h>

#include "airframe.h"
#include "variables.h"

#define R(name) (m->real[VR_##name])
#define RV(name) REAL_VECTOR(m, name)

enum { OMEGA = 0, CURRENT = N_MOTORS, SOC = 2 * N_MOTORS };
/* Mode of a motor: conducting freely, or held at a bound of its current. */
enum { CONDUCTING = 0, COASTING, AT_MAX, AT_MIN };
#define MAX_SWITCHES 32 /* mode switches located per sub-step; beyond, the step projects */
#define CROSSING_TOLERANCE 1e-12 /* a crossing is located to this fraction of the sub-step */
#define CROSSING_ITERATIONS 100  /* Illinois iterations at most per crossing */
#define PHI3_SERIES_TERMS 20     /* where |hA| < 0.5 the 20th term is below 1e-28 of phi3 */
#define CONFLUENT 1e-6           /* eigenvalues closer than this, relatively, count as one */
#define CONFLUENT_SPLIT 1e-5     /* relative split of confluent eigenvalues (error O(split^2)) */

/* 2x2 row-major functions of h A: exp(hA), exp(hA/2), (h/2) phi1(hA/2), and the
 * ETDRK4 weights h(phi1 - 3 phi2 + 4 phi3), h(phi2 - 2 phi3), h(-phi2 + 4 phi3). */
typedef struct {
    double h, e[4], e2[4], q[4], f1[4], f2[4], f3[4];
} Etd;

typedef struct {
    double x[N_STATES];
    double v[N_MOTORS][3]; /* unit field directions */
    Etd main;              /* for the sub-step of the last doStep */
    int mode[N_MOTORS];
    int saturated[N_MOTORS];
} Data;

const size_t MODEL_DATA_SIZE = sizeof(Data);

static double clamp01(double c) { return c < 0.0 ? 0.0 : (c > 1.0 ? 1.0 : c); }
static double command(ModelInstance *m, int n) { return clamp01(RV(c)[n]); }

static double battery_current(ModelInstance *m, const double *x) {
    double total = 0.0;
    int n;
    for (n = 0; n < N_MOTORS; n++) total += command(m, n) * x[CURRENT + n];
    return total;
}

static double battery_voltage(ModelInstance *m, const double *x) {
    double s = x[SOC];
    double cell = R(ocv0) + s * (R(ocv1) + s * (R(ocv2) + s * R(ocv3)));
    return R(n_cells) * cell - R(R_b) * battery_current(m, x);
}

/* The voltage the ESC applies beyond the back-EMF, c u - k_e omega (V). */
static double drive(ModelInstance *m, const double *x, double u, int n) {
    return command(m, n) * u - R(k_e) * x[OMEGA + n];
}

static double lower_bound(ModelInstance *m) {
    return m->boolean[VB_regenerative] ? -R(i_max) : 0.0;
}

/* The mode each motor takes at state x; a current at a bound is set exactly on it. */
static void select_modes(ModelInstance *m, Data *d, double *x) {
    double u = battery_voltage(m, x), low = lower_bound(m);
    int n;
    for (n = 0; n < N_MOTORS; n++) {
        double i = x[CURRENT + n], v = drive(m, x, u, n);
        if (i <= low && v - R(R_m) * low <= 0.0) {
            d->mode[n] = low == 0.0 ? COASTING : AT_MIN;
            x[CURRENT + n] = low;
        } else if (i >= R(i_max) && v - R(R_m) * R(i_max) >= 0.0) {
            d->mode[n] = AT_MAX;
            x[CURRENT + n] = R(i_max);
        } else {
            d->mode[n] = CONDUCTING;
        }
    }
}

/* How far each motor is from leaving its mode, worst of the four: negative once one has. */
static double margin(ModelInstance *m, const Data *d, const double *x) {
    double u = battery_voltage(m, x), low = lower_bound(m), worst = INFINITY, g;
    int n;
    for (n = 0; n < N_MOTORS; n++) {
        double i = x[CURRENT + n], v = drive(m, x, u, n);
        switch (d->mode[n]) {
        case CONDUCTING: g = fmin(i - low, R(i_max) - i); break;
        case AT_MAX: g = (v - R(R_m) * R(i_max)) / R(R_m); break; /* current would fall */
        default: g = (R(R_m) * low - v) / R(R_m); break;          /* current would rise */
        }
        worst = fmin(worst, g);
    }
    return worst;
}

/* The slow remainder N(x) of each motor in its mode, and dsoc. */
static void nonstiff(ModelInstance *m, const Data *d, const double *x, double *nx) {
    double u = battery_voltage(m, x);
    int n;
    for (n = 0; n < N_MOTORS; n++) {
        double w = x[OMEGA + n], drag = -R(k_m) * w * fabs(w) / R(J_r);
        if (d->mode[n] == CONDUCTING) {
            nx[OMEGA + n] = drag;
            nx[CURRENT + n] = command(m, n) * u / R(L_m);
        } else {
            nx[OMEGA + n] = drag + R(k_e) * x[CURRENT + n] / R(J_r);
            nx[CURRENT + n] = 0.0;
        }
    }
    nx[SOC] = -battery_current(m, x) / R(capacity);
}

/* phi_k(z) = sum_j z^j / (j + k)!; phi_k = 1/k! + z phi_(k+1). phi3 by its series near 0,
 * where the closed form cancels, and in closed form elsewhere. Index 0 is exp. */
static void phi0123(double complex z, double complex p[4]) {
    if (cabs(z) < 0.5) {
        double complex term = 1.0 / 6.0, sum = 0.0;
        int j;
        for (j = 0; j < PHI3_SERIES_TERMS; j++) {
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

static void etd_coefficients(ModelInstance *m, Etd *c, double h) {
    const double a[4] = {0.0, R(k_e) / R(J_r), -R(k_e) / R(L_m), -R(R_m) / R(L_m)};
    double trace = a[0] + a[3], det = a[0] * a[3] - a[1] * a[2];
    double complex root = csqrt((double complex)(trace * trace - 4.0 * det));
    double complex l1 = 0.5 * (trace + root), l2 = 0.5 * (trace - root);
    double complex p1[4], p2[4], h1[4], h2[4], w1[3], w2[3];
    if (cabs(l1 - l2) < CONFLUENT * cabs(l1)) { /* confluent: split by a negligible amount */
        l1 += CONFLUENT_SPLIT * cabs(l1);
        l2 -= CONFLUENT_SPLIT * cabs(l2);
    }
    phi0123(h * l1, p1);
    phi0123(h * l2, p2);
    phi0123(0.5 * h * l1, h1);
    phi0123(0.5 * h * l2, h2);
    interpolate(a, l1, l2, p1[0], p2[0], 1.0, c->e);
    interpolate(a, l1, l2, h1[0], h2[0], 1.0, c->e2);
    interpolate(a, l1, l2, h1[1], h2[1], 0.5 * h, c->q);
    w1[0] = p1[1] - 3.0 * p1[2] + 4.0 * p1[3];
    w2[0] = p2[1] - 3.0 * p2[2] + 4.0 * p2[3];
    w1[1] = p1[2] - 2.0 * p1[3];
    w2[1] = p2[2] - 2.0 * p2[3];
    w1[2] = -p1[2] + 4.0 * p1[3];
    w2[2] = -p2[2] + 4.0 * p2[3];
    interpolate(a, l1, l2, w1[0], w2[0], h, c->f1);
    interpolate(a, l1, l2, w1[1], w2[1], h, c->f2);
    interpolate(a, l1, l2, w1[2], w2[2], h, c->f3);
    c->h = h;
}

/* out = M1 y + M2 n on motor k's (omega, i) pair, M1, M2 2x2 row-major. */
static void pair(const double m1[4], const double m2[4], const double *y, const double *n, int k, double *out) {
    double w = y[OMEGA + k], i = y[CURRENT + k], nw = n[OMEGA + k], ni = n[CURRENT + k];
    out[OMEGA + k] = m1[0] * w + m1[1] * i + m2[0] * nw + m2[1] * ni;
    out[CURRENT + k] = m1[2] * w + m1[3] * i + m2[2] * nw + m2[3] * ni;
}

/* An ETDRK4 stage, out = exp(hA/2) y + (h/2) phi1(hA/2) n; A = 0 for a motor at a bound. */
static void stage(const Data *d, const Etd *c, const double *y, const double *n, double *out) {
    const double one[4] = {1.0, 0.0, 0.0, 1.0}, half[4] = {0.5 * c->h, 0.0, 0.0, 0.5 * c->h};
    int k;
    for (k = 0; k < N_MOTORS; k++) {
        if (d->mode[k] == CONDUCTING) pair(c->e2, c->q, y, n, k, out);
        else pair(one, half, y, n, k, out);
    }
    out[SOC] = y[SOC] + 0.5 * c->h * n[SOC];
}

/* One ETDRK4 step of length c->h from x to out (which may be x), the modes held. */
static void advance(ModelInstance *m, const Data *d, const Etd *c, const double *x, double *out) {
    double nu[N_STATES], na[N_STATES], nb[N_STATES], nc[N_STATES];
    double a[N_STATES], b[N_STATES], s[N_STATES], tmp[N_STATES];
    const double one[4] = {1.0, 0.0, 0.0, 1.0}, sixth[4] = {c->h / 6.0, 0.0, 0.0, c->h / 6.0};
    int k;
    nonstiff(m, d, x, nu);
    stage(d, c, x, nu, a);
    nonstiff(m, d, a, na);
    stage(d, c, x, na, b);
    nonstiff(m, d, b, nb);
    for (k = 0; k < N_STATES; k++) tmp[k] = 2.0 * nb[k] - nu[k];
    stage(d, c, a, tmp, s);
    nonstiff(m, d, s, nc);
    for (k = 0; k < N_STATES; k++) tmp[k] = na[k] + nb[k];
    out[SOC] = x[SOC] + c->h / 6.0 * (nu[SOC] + 2.0 * tmp[SOC] + nc[SOC]);
    for (k = 0; k < N_MOTORS; k++) {
        int held = d->mode[k] != CONDUCTING;
        const double *e = held ? one : c->e, *f1 = held ? sixth : c->f1, *f2 = held ? sixth : c->f2,
                     *f3 = held ? sixth : c->f3;
        double w = x[OMEGA + k], i = x[CURRENT + k];
        double uw = nu[OMEGA + k], ui = nu[CURRENT + k], sw = tmp[OMEGA + k], si = tmp[CURRENT + k];
        double cw = nc[OMEGA + k], ci = nc[CURRENT + k];
        out[OMEGA + k] = e[0] * w + e[1] * i + f1[0] * uw + f1[1] * ui + 2.0 * (f2[0] * sw + f2[1] * si) +
                         f3[0] * cw + f3[1] * ci;
        out[CURRENT + k] = e[2] * w + e[3] * i + f1[2] * uw + f1[3] * ui + 2.0 * (f2[2] * sw + f2[3] * si) +
                           f3[2] * cw + f3[3] * ci;
    }
}

/* Advance x by one sub-step h, cutting it where a motor's current reaches a bound or leaves
 * one, so that each piece is smooth. */
static void substep(ModelInstance *m, Data *d, double h) {
    double remaining = h, trial[N_STATES];
    int switches;
    if (h != d->main.h) etd_coefficients(m, &d->main, h);
    for (switches = 0; remaining > 0.0; switches++) {
        Etd piece;
        const Etd *c = &d->main;
        select_modes(m, d, d->x);
        if (remaining != h) {
            etd_coefficients(m, &piece, remaining);
            c = &piece;
        }
        advance(m, d, c, d->x, trial);
        if (margin(m, d, trial) >= 0.0 || switches >= MAX_SWITCHES) break;
        {   /* Illinois on the fraction s of the remaining step: margin >= 0 at lo, < 0 at hi */
            double lo = 0.0, hi = 1.0, g_lo = margin(m, d, d->x), g_hi = margin(m, d, trial);
            int side = 0, k;
            if (g_lo < 0.0) g_lo = 0.0; /* on the bound already: the crossing is at once */
            for (k = 0; k < CROSSING_ITERATIONS && hi - lo > CROSSING_TOLERANCE; k++) {
                double s = hi - g_hi * (hi - lo) / (g_hi - g_lo), g;
                if (!(s > lo && s < hi)) s = 0.5 * (lo + hi);
                etd_coefficients(m, &piece, s * remaining);
                advance(m, d, &piece, d->x, trial);
                g = margin(m, d, trial);
                if (g >= 0.0) {
                    lo = s;
                    g_lo = g;
                    if (side == -1) g_hi *= 0.5;
                    side = -1;
                } else {
                    hi = s;
                    g_hi = g;
                    if (side == 1) g_lo *= 0.5;
                    side = 1;
                }
            }
            /* end just past the switch, where the new mode's condition holds */
            etd_coefficients(m, &piece, hi * remaining);
            advance(m, d, &piece, d->x, d->x);
            remaining -= hi * remaining;
        }
    }
    if (remaining > 0.0) {
        int k;
        for (k = 0; k < N_STATES; k++) d->x[k] = trial[k];
        /* a sub-step that ran out of located switches projects on the bounds */
        for (k = CURRENT; k < CURRENT + N_MOTORS; k++) d->x[k] = fmin(fmax(d->x[k], lower_bound(m)), R(i_max));
    }
}

Status model_initialize(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const char *names[] = {"R_m", "L_m", "k_e", "J_r", "n_cells", "capacity", "i_max", "sub_step"};
    const double values[] = {R(R_m), R(L_m), R(k_e), R(J_r), R(n_cells), R(capacity), R(i_max), R(sub_step)};
    unsigned i;
    int n;
    for (i = 0; i < sizeof values / sizeof values[0]; i++) {
        if (!(values[i] > 0.0) || !isfinite(values[i])) {
            log_error(m, "parameter %s = %g must be positive and finite", names[i], values[i]);
            return STATUS_ERROR;
        }
    }
    if (!(R(k_m) >= 0.0) || !(R(R_b) >= 0.0) || !(R(soc0) >= 0.0 && R(soc0) <= 1.0)) {
        log_error(m, "k_m = %g and R_b = %g must be non-negative and soc0 = %g within [0, 1]",
                  R(k_m), R(R_b), R(soc0));
        return STATUS_ERROR;
    }
    for (n = 0; n < N_MOTORS; n++) {
        const double *v = RV(v) + 3 * n;
        double norm = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(norm > 0.0) || !isfinite(norm)) {
            log_error(m, "field direction of motor %d is zero or not finite; give v%d_x/y/z", n + 1,
                      n + 1);
            return STATUS_ERROR;
        }
        for (i = 0; i < 3; i++) d->v[n][i] = v[i] / norm;
        d->x[OMEGA + n] = R(omega0);
        d->x[CURRENT + n] = R(k_m) * R(omega0) * fabs(R(omega0)) / R(k_e);
        if (fabs(d->x[CURRENT + n]) > R(i_max)) {
            log_error(m, "omega0 = %g rad/s needs a motor current of %.3g A, beyond i_max = %g A: lower "
                      "omega0 or raise i_max", R(omega0), d->x[CURRENT + n], R(i_max));
            return STATUS_ERROR;
        }
    }
    d->x[SOC] = R(soc0);
    d->main.h = -1.0;
    select_modes(m, d, d->x);
    return STATUS_OK;
}

Status model_do_step(ModelInstance *m, double t, double h) {
    Data *d = (Data *)m->data;
    int n = substep_count(m, h, R(sub_step), "sub_step"), k;
    if (n == 0) return STATUS_ERROR;
    for (k = 0; k < N_MOTORS; k++) {
        double c = RV(c)[k];
        int outside = c < 0.0 || c > 1.0;
        if (outside && !d->saturated[k])
            log_warning(m, "c%d = %g at t = %g is outside [0, 1]: saturated", k + 1, c, m->time);
        d->saturated[k] = outside;
    }
    for (k = 0; k < n; k++) {
        substep(m, d, h / n);
        if (d->x[SOC] < 0.0) { /* an empty battery is the end of the flight, not a negative charge */
            log_error(m, FMI_NAME(DoStep) ": the battery is empty at t = %g s (state of charge %g); raise capacity "
                         "(%g A.s) or soc0 (%g), or shorten the run",
                      t + (k + 1) * h / n, d->x[SOC], R(capacity), R(soc0));
            return STATUS_ERROR;
        }
    }
    return STATUS_OK;
}

void model_outputs(ModelInstance *m) {
    Data *d = (Data *)m->data;
    const double *x = d->x;
    int n, a;
    for (a = 0; a < 3; a++) RV(b_d)[a] = 0.0;
    for (n = 0; n < N_MOTORS; n++) {
        double supply = command(m, n) * x[CURRENT + n], field = RV(kappa)[n] * supply;
        RV(omega_r)[n] = x[OMEGA + n];
        RV(domega_r)[n] = (R(k_e) * x[CURRENT + n] - R(k_m) * x[OMEGA + n] * fabs(x[OMEGA + n])) / R(J_r);
        RV(i)[n] = x[CURRENT + n];
        RV(i_s)[n] = supply;
        for (a = 0; a < 3; a++) {
            RV(b_d_motor)[3 * n + a] = field * d->v[n][a];
            RV(b_d)[a] += field * d->v[n][a];
        }
    }
    R(i_batt) = battery_current(m, x);
    R(u_batt) = battery_voltage(m, x);
    R(soc) = x[SOC];
}
