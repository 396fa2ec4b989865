/* angles.h: a fast atan2 for the kernels that turn vectors into angles (edges.cl, curves.cl). */
#ifndef ANGLES_H
#define ANGLES_H

/* atan2(gy, gx) by Cephes' atanf polynomial (relative error about 2e-7 on [0, tan(pi/8)]), in selects
 * only, so a vector path stays vector code: PoCL's own atan2 cost ten times the rest of Canny's
 * gradient kernel, and twice the whole arc filter of the curves' tangents. The ratio of the smaller to
 * the larger component is folded about tan(pi/8) with one division, then the octant is restored. A zero
 * vector has direction 0. DEFINE_ATAN2(name, F, I) defines it for a float type F and the int type I of
 * its comparisons: (float, int), or vectors such as (float16, int16). */
#define DEFINE_ATAN2(NAME, F, I)                                                           \
    __attribute__((always_inline)) inline F NAME(F gy, F gx)                               \
    {                                                                                      \
        F ax = fabs(gx), ay = fabs(gy), lo = min(ax, ay), hi = max(ax, ay);                \
        I folded = lo > 0.414213562373095f * hi;                                           \
        F t = (folded ? lo - hi : lo) / (folded ? lo + hi : hi), z = t * t;                \
        F a = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z   \
               - 3.33329491539e-1f) * z * t + t;                                           \
        a = folded ? a + M_PI_4_F : a;                                                     \
        a = ay > ax ? M_PI_2_F - a : a;                                                    \
        a = gx < 0.0f ? M_PI_F - a : a;                                                    \
        a = hi > 0.0f ? a : 0.0f;                                                          \
        return gy < 0.0f ? -a : a;                                                         \
    }

#endif
