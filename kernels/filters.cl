/* filters.cl: the binomial approximation to the Gaussian, seed section "Edge detection" (Zero-crossings):
 * "only integer addition, shifting, and local communication on the 2D mesh".
 *
 * One pass convolves with [1 2 1]/4 along x and along y at once (the 3 x 3 mask [1 2 1]^T [1 2 1] / 16),
 * reading the eight NEWS neighbours; borders repeat the edge pixel. n passes give the binomial of
 * order 2n in each direction, variance n / 2.
 *
 * Defines: T (uchar|int|float), T_IS_FLOAT.
 */
#include "vmcl.h"

#if T_IS_FLOAT
#define ACC float
#define NORMALISE(s) ((s) * 0.0625f)
#else
/* Integers: add, then shift with rounding to nearest (ties up); long holds 16 * INT_MAX. */
#define ACC long
#define NORMALISE(s) (((s) + 8) >> 4)
#endif

__kernel void binomial_pass(__global const T *in, __global T *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= W || y >= H) return;
    long xl = max(x - 1, 0L), xr = min(x + 1, W - 1);
    long yu = max(y - 1, 0L), yd = min(y + 1, H - 1);
    __global const T *up = in + IDX3(0, yu, p, W, H);
    __global const T *mid = in + IDX3(0, y, p, W, H);
    __global const T *down = in + IDX3(0, yd, p, W, H);
    ACC s = (ACC)up[xl] + 2 * (ACC)up[x] + (ACC)up[xr]
          + 2 * ((ACC)mid[xl] + 2 * (ACC)mid[x] + (ACC)mid[xr])
          + (ACC)down[xl] + 2 * (ACC)down[x] + (ACC)down[xr];
    out[IDX3(x, y, p, W, H)] = (T)NORMALISE(s);
}
