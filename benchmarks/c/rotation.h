/* Rotation matrix of a unit quaternion (scalar first), body to inertial frame: the one
   transcription both reference programs use, written as estimators/core.py computes it. */
#ifndef QUADCOSIM_BENCHMARK_ROTATION_H
#define QUADCOSIM_BENCHMARK_ROTATION_H

static inline void rotation_of_quaternion(double q0, double q1, double q2, double q3, double r[3][3]) {
    r[0][0] = 1.0 - 2.0 * (q2 * q2 + q3 * q3);
    r[0][1] = 2.0 * (q1 * q2 - q0 * q3);
    r[0][2] = 2.0 * (q1 * q3 + q0 * q2);
    r[1][0] = 2.0 * (q1 * q2 + q0 * q3);
    r[1][1] = 1.0 - 2.0 * (q1 * q1 + q3 * q3);
    r[1][2] = 2.0 * (q2 * q3 - q0 * q1);
    r[2][0] = 2.0 * (q1 * q3 - q0 * q2);
    r[2][1] = 2.0 * (q2 * q3 + q0 * q1);
    r[2][2] = 1.0 - 2.0 * (q1 * q1 + q2 * q2);
}

#endif
