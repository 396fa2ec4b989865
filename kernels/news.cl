/* news.cl: NEWS communication, seed section "The Connection Machine": every processor of the grid takes
 * the value of the processor (dx, dy) away, all in the same direction at once.
 *
 * Defines: T (element type), BORDER (0 zero, 1 clamp, 2 wrap): what a processor gets whose source lies
 * outside the field.
 */
#include "vmcl.h"

/* Position of source coordinate v on an axis of length n under the border rule; -1 means "zero". */
inline long border_index(long v, long n)
{
#if BORDER == 0
    return (v < 0 || v >= n) ? -1 : v;
#elif BORDER == 1
    return clamp(v, 0L, n - 1);
#else
    long m = v % n;
    return m < 0 ? m + n : m;
#endif
}

/* out[p, y, x] = field[p, y - dy, x - dx]: the field moves dx to the right and dy down. */
__kernel void shift(__global const T *field, __global T *out, long W, long H, long dx, long dy)
{
    long x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= W || y >= H) return;
    long sx = border_index(x - dx, W), sy = border_index(y - dy, H);
    out[IDX3(x, y, p, W, H)] = (sx < 0 || sy < 0) ? (T)0 : field[IDX3(sx, sy, p, W, H)];
}

/* A plain copy, the yardstick for every streaming kernel's bandwidth: VEC elements per work-item, so it
 * measures the memory system rather than the cost of scheduling one work-item per element. */
__kernel void copy(__global const T *src, __global T *dst, long n)
{
    long i = get_global_id(0) * VEC;
    if (i + VEC <= n) {
        VSTORE(VLOAD(src + i), dst + i);
    } else {
        for (; i < n; i++) dst[i] = src[i];
    }
}
