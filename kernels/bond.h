/* bond.h: rho(f_i, f_j), the smoothness cost of the bond between two pixels when no line breaks it
 * (kernels/mrf.cl's energy; kernels/pseudolikelihood.cl reads it at kappa = 1 as the coupling's feature).
 * Needs NCOMP (components) and KIND (0 smooth: |f_i - f_j|^2; 1 constant: kappa [f_i != f_j]) defined. */
#ifndef BOND_H
#define BOND_H

inline float bond_cost(__global const float *f, long i, long j, float kappa)
{
#if KIND == 0
    float s = 0.0f;
    for (int c = 0; c < NCOMP; ++c) {
        float d = f[i * NCOMP + c] - f[j * NCOMP + c];
        s += d * d;
    }
    return s;
#else
    return f[i] != f[j] ? kappa : 0.0f;
#endif
}

#endif
