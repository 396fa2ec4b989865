/* cm_filters.cl, driven by vmcl/cm/filters.py.
 * Local filters on the mesh. The binomial approximation to the Gaussian, seed section "Edge
 * detection" (Zero-crossings): "only integer addition, shifting, and local communication on the 2D mesh";
 * and the window maximum (grey-level dilation by a square), one axis per pass.
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
#define TO_T(v) (v)
#elif defined(T_IS_UCHAR)
/* Integers: add, then shift with rounding to nearest (ties up). 16 * 255 fits an int. */
#define ACC int
#define NORMALISE(s) (((s) + 8) >> 4)
#define TO_T(v) VCAT(convert_, T16)(v)
#else
/* long holds 16 * INT_MAX. */
#define ACC long
#define NORMALISE(s) (((s) + 8) >> 4)
#define TO_T(v) VCAT(convert_, T16)(v)
#endif
#define T16 VCAT(T, 16)
#define ACC16 VCAT(ACC, 16)
#define LOAD(p) VCAT(convert_, ACC16)(vload16(0, (p)))

/* Sum of one mask row: [1 2 1] around the 16 pixels from p. */
#define ROW16(p) (LOAD((p) - 1) + 2 * LOAD(p) + LOAD((p) + 1))
#define ROW1(r, x) ((ACC)(r)[max(x - 1, 0L)] + 2 * (ACC)(r)[x] + (ACC)(r)[min(x + 1, W - 1)])

/* Float sums of 16 pixels overflow for values past FLT_MAX / 16 (about 2e37): where one did, the sum
 * is taken again with every weight divided by 16 before it is applied (1/4 along each axis). Powers of
 * two scale normal values exactly, so that is the same sum, rounded alike, without the overflow; lanes
 * that did not overflow keep their own. */
#define ROW16Q(p) (0.25f * LOAD((p) - 1) + 0.5f * LOAD(p) + 0.25f * LOAD((p) + 1))
#define ROW1Q(r, x) (0.25f * (r)[max(x - 1, 0L)] + 0.5f * (r)[x] + 0.25f * (r)[min(x + 1, W - 1)])
#define BIG_SUM(s, q) (isinf(s) ? (q) : NORMALISE(s))

/* Work-item (k, y, p) smooths pixels [16k, 16k + 16) of row y of plane p: one vector step in the
 * interior, pixel by pixel where the window meets the left or right border (or the row ends). */
__kernel void binomial_pass(__global const T *in, __global T *out, long W, long H)
{
    long k = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    long x0 = k * 16;
    if (x0 >= W || y >= H) return;
    __global const T *up = in + IDX3(0, max(y - 1, 0L), p, W, H);
    __global const T *mid = in + IDX3(0, y, p, W, H);
    __global const T *down = in + IDX3(0, min(y + 1, H - 1), p, W, H);
    __global T *target = out + IDX3(0, y, p, W, H);
    if (x0 >= 1 && x0 + 17 <= W) {
        ACC16 s = ROW16(up + x0) + 2 * ROW16(mid + x0) + ROW16(down + x0);
#if T_IS_FLOAT
        vstore16(any(isinf(s)) ? BIG_SUM(s, 0.25f * ROW16Q(up + x0) + 0.5f * ROW16Q(mid + x0)
                                         + 0.25f * ROW16Q(down + x0)) : NORMALISE(s), 0, target + x0);
#else
        vstore16(TO_T(NORMALISE(s)), 0, target + x0);
#endif
    } else {
        for (long x = x0; x < min(x0 + 16, W); x++) {
            ACC s = ROW1(up, x) + 2 * ROW1(mid, x) + ROW1(down, x);
#if T_IS_FLOAT
            target[x] = BIG_SUM(s, 0.25f * ROW1Q(up, x) + 0.5f * ROW1Q(mid, x) + 0.25f * ROW1Q(down, x));
#else
            target[x] = (T)NORMALISE(s);
#endif
        }
    }
}

#if T_IS_FLOAT  /* the program is also built for the binomial's integer types */
/* One axis of the window maximum: out(x, y) is the largest of in over x - r .. x + r (along_rows) or
 * y - r .. y + r, within the field; one work-item per pixel of every plane. The window is small (the
 * matcher's patch), so a plain loop beats a running structure. NaN is passed over (fmax), so a pixel
 * whose window holds only NaN gets NaN. */
__kernel void window_max_pass(__global const T *in, __global T *out, long W, long H, long r, int along_rows)
{
    long x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= W || y >= H) return;
    __global const T *plane = in + (size_t)p * H * W;
    long at = along_rows ? x : y, n = along_rows ? W : H, step = along_rows ? 1 : W;
    long base = along_rows ? y * W : x;
    T best = NAN;
    for (long j = max(at - r, 0L); j <= min(at + r, n - 1); j++) best = fmax(best, plane[base + j * step]);
    out[(size_t)p * H * W + y * W + x] = best;
}
#endif
