/* Quaternion helpers shared by the models (scalar first, Hamilton). */
#ifndef QUATERNION_H
#define QUATERNION_H

/* r = R(q) = I + 2 q0 S(qv) + 2 S(qv)^2, body to NED, row-major. */
static inline void rotation_from_quaternion(const double *q, double r[9]) {
    double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    r[0] = 1.0 - 2.0 * (q2 * q2 + q3 * q3);
    r[1] = 2.0 * (q1 * q2 - q0 * q3);
    r[2] = 2.0 * (q1 * q3 + q0 * q2);
    r[3] = 2.0 * (q1 * q2 + q0 * q3);
    r[4] = 1.0 - 2.0 * (q1 * q1 + q3 * q3);
    r[5] = 2.0 * (q2 * q3 - q0 * q1);
    r[6] = 2.0 * (q1 * q3 - q0 * q2);
    r[7] = 2.0 * (q2 * q3 + q0 * q1);
    r[8] = 1.0 - 2.0 * (q1 * q1 + q2 * q2);
}

#endif
