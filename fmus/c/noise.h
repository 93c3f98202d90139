/* Counter-based white noise shared by the models: draw `channel` of sample `k` is a pure
 * function of (seed, k, channel), so a stream does not depend on the co-simulation step. */
#ifndef NOISE_H
#define NOISE_H

#include <math.h>
#include <stdint.h>

static inline uint64_t splitmix64(uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Standard normal draw number `channel` of sample `k` (Box-Muller on two hashed uniforms). */
#define KEYS_PER_SAMPLE 64u /* sample k owns the keys 64 k to 64 k + 63: 32 channels, two keys apart */

static inline double gaussian(int seed, int64_t k, int channel) {
    const double two_pi = 6.283185307179586;
    uint64_t key = splitmix64((uint64_t)(uint32_t)seed) ^ ((uint64_t)k * KEYS_PER_SAMPLE + 2u * (uint64_t)channel);
    double u1 = ((double)(splitmix64(key) >> 11) + 1.0) * 0x1.0p-53; /* (0, 1] */
    double u2 = (double)(splitmix64(key ^ 0xD1B54A32D192ED03ull) >> 11) * 0x1.0p-53;
    return sqrt(-2.0 * log(u1)) * cos(two_pi * u2);
}

#endif
