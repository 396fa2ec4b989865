/* reduce.cl: the Connection Machine's global reductions (sum, max, min, logical AND and OR of a field,
 * returned to the host) and histograms, global or per tile: the local histograms of the paper's noise
 * estimation ("Edge detection", Noise Estimation).
 *
 * Defines: T (element type), OP (OP_PLUS|OP_MAX|OP_MIN|OP_AND|OP_OR), ACC (accumulator type),
 * T_IS_FLOAT. Results are deterministic: every reduction runs in a fixed order (a serial pass per chunk,
 * then a serial pass over the chunk results), and histograms count with integer atomics only.
 */
#include "vmcl.h"

#if OP == OP_PLUS
#define IDENTITY ((ACC)0)
#define COMBINE(a, b) ((a) + (b))
#elif T_IS_FLOAT && (OP == OP_MAX || OP == OP_MIN)
/* fmax and fmin return the other argument when one is NaN (and NaN for two), so NaN elements are skipped
 * and a field of NaN alone reduces to NaN on every device. (max and min leave NaN undefined: PoCL gave NaN
 * for an all-NaN field, NVIDIA's OpenCL the identity, infinity.) */
#define IDENTITY ((ACC)NAN)
#define COMBINE(a, b) (OP == OP_MAX ? fmax((a), (b)) : fmin((a), (b)))
#elif OP == OP_MAX
#define IDENTITY ((ACC)T_LOWEST)
#define COMBINE(a, b) max((a), (b))
#elif OP == OP_MIN || OP == OP_AND
#define IDENTITY ((ACC)(OP == OP_AND ? 1 : T_HIGHEST))
#define COMBINE(a, b) min((a), (b))
#elif OP == OP_OR
#define IDENTITY ((ACC)0)
#define COMBINE(a, b) max((a), (b))
#endif

/* Logical AND and OR are min and max over truth values 0/1. */
#define ACCV VCAT(ACC, 16)
#if OP == OP_AND || OP == OP_OR
#define LOAD16(p) (VCAT(convert_, ACCV)(vload16(0, (p)) != (VCAT(T, 16))0) & (ACCV)1)
#define LOAD1(p) ((ACC)(*(p) != 0))
#else
#define LOAD16(p) VCAT(convert_, ACCV)(vload16(0, (p)))
#define LOAD1(p) ((ACC)*(p))
#endif

/* Float sums use Kahan's compensated summation, so the result stays within a few ulps of the exact sum
 * however many elements there are; everything else accumulates directly. */
#define KAHAN (OP == OP_PLUS && T_IS_FLOAT)

#if KAHAN
/* A compensation that is not finite (the sum reached an infinity, or overflowed) is dropped: carried on,
 * inf - inf would turn an infinite sum into NaN. */
#define KAHAN_ADD(acc, c, v) { __typeof__(acc) y_ = (v) - (c); __typeof__(acc) t_ = (acc) + y_; \
                               __typeof__(acc) c_ = (t_ - (acc)) - y_; \
                               (c) = (c_ - c_ == (__typeof__(acc))0) ? c_ : (__typeof__(acc))0; (acc) = t_; }
#endif

/* Reduce elements [begin, end) of x, writing the chunk result (and its compensation) to partial[g].
 * Sixteen lanes accumulate side by side (sixteen independent chains, one vector load per step), then
 * fold in lane order, so the result does not depend on the device. */
__kernel void reduce_chunks(__global const T *x, __global ACC *partial, __global ACC *compensation,
                            long n, long chunk)
{
    long g = get_global_id(0);
    if (g * chunk >= n) return;
    long begin = g * chunk, end = min(begin + chunk, n);
    long vec_end = begin + (end - begin) / 16 * 16;
    ACCV lanes = (ACCV)IDENTITY;
    ACC acc = IDENTITY, c = 0;
#if KAHAN
    ACCV lane_c = (ACCV)0;
    for (long i = begin; i < vec_end; i += 16) KAHAN_ADD(lanes, lane_c, LOAD16(x + i))
    ACC lane_acc[16], lane_comp[16];
    vstore16(lanes, 0, lane_acc);
    vstore16(lane_c, 0, lane_comp);
    for (int j = 0; j < 16; j++) KAHAN_ADD(acc, c, lane_acc[j] - lane_comp[j])
    for (long i = vec_end; i < end; i++) KAHAN_ADD(acc, c, LOAD1(x + i))
#else
    for (long i = begin; i < vec_end; i += 16) lanes = COMBINE(lanes, LOAD16(x + i));
    ACC lane_acc[16];
    vstore16(lanes, 0, lane_acc);
    for (int j = 0; j < 16; j++) acc = COMBINE(acc, lane_acc[j]);
    for (long i = vec_end; i < end; i++) acc = COMBINE(acc, LOAD1(x + i));
#endif
    partial[g] = acc;
    compensation[g] = c;
}

/* One work-item folds the chunk results in order. */
__kernel void reduce_partials(__global const ACC *partial, __global const ACC *compensation,
                              __global ACC *out, long count)
{
    if (get_global_id(0) != 0) return;
    ACC acc = IDENTITY;
#if KAHAN
    ACC c = 0;
    for (long g = 0; g < count; g++) KAHAN_ADD(acc, c, partial[g] - compensation[g])
#else
    for (long g = 0; g < count; g++) acc = COMBINE(acc, partial[g]);
#endif
    out[0] = acc;
}

/* Histogram of tile g of a (H, W) field cut into tiles of th x tw (edge tiles may be smaller): bin
 * floor((v - lo) * scale) for lo <= v <= hi (v == hi and rounding up to `bins` both go to the last
 * bin); values outside [lo, hi] and NaN are not counted. The work-group counts into local memory, then
 * writes its tile's row of `out` (per-tile mode) or adds it into the one histogram (accumulate).
 * SHARED_COUNTS = 0 (work-groups of one work-item) counts with plain increments. TO_TOP = 1 takes hi
 * from top[0], a maximum computed on the device (lo + 1 when it is not above lo or NaN; an infinite top
 * makes every bin infinitely wide, so every value from lo on goes to bin 0), and scale from it as the
 * host would, so the host never waits for the range; otherwise `top` is not read.
 *
 * A range too narrow (bins / (hi - lo) overflows) or too wide (hi - lo overflows) for float32's
 * exponent is binned as if the exponent were unbounded: v and lo are first multiplied by a power of two
 * that brings the range near 1, which is exact, so the bins are the same rule's. Bin positions are
 * clamped to [0, bins - 1] in float before the conversion to int, so no value of v, lo, hi or top
 * (infinite, NaN or subnormal) can index outside the counts. */
inline float range_prescale(float lo, float hi)
{
    float width = hi - lo, extent = isfinite(width) ? width : fmax(fabs(lo), fabs(hi));
    /* ilogb of 0, infinity or NaN is far outside the clamp: the clamp keeps the factor finite. */
    return ldexp(1.0f, clamp(-ilogb(extent), -126, 127));
}

#if T_IS_FLOAT
#define RELATIVE(v) ((float)(v))
#define RELATIVE16(v) convert_float16(v)
#else
/* An integer is taken relative to `base` (the range's start, floored, on the host) exactly, before float32
 * rounds it: int32 values past 2^24 would otherwise share bins far apart. lo and hi come relative too. */
#define RELATIVE(v) ((float)((long)(v) - base))
#define RELATIVE16(v) convert_float16(convert_long16(v) - base)
#endif

__kernel void histogram_tiles(__global const T *x, __global int *out, __local int *counts,
                              __global const float *top, long W, long H, long th, long tw, long tiles_x,
                              float lo, float hi, float scale, int bins, int accumulate, long base)
{
#if TO_TOP
#if T_IS_FLOAT
    float reached = top[0];
#else
    /* An integer field's maximum in float32 is rounded, past 2^24 maybe down, below the largest value:
     * every integer up to the next float32 above it is counted, taken relative to base exactly. */
    float up = floor(nextafter(top[0], INFINITY));
    float reached = isfinite(up) ? (float)((long)clamp(up, -4.0e18f, 4.0e18f) - base) : top[0];
#endif
    hi = reached > lo ? reached : lo + 1.0f;
    scale = (float)bins / (hi - lo);
#endif
    float prescale = 1.0f;
    if (!(isfinite(hi - lo) && isfinite(scale))) {
        prescale = range_prescale(lo, hi);
        scale = (float)bins / (hi * prescale - lo * prescale);
    }
    float lo_scaled = lo * prescale, last = (float)(bins - 1);
    long g = get_group_id(0);
    int lid = get_local_id(0), size = get_local_size(0);
    for (int b = lid; b < bins; b += size) counts[b] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    long y0 = (g / tiles_x) * th, x0 = (g % tiles_x) * tw;
    long rows = min(th, H - y0), cols = min(tw, W - x0);
    for (long r = 0; r < rows; r++) {
        __global const T *row = x + (y0 + r) * W + x0;
        long c = lid;
#if !SHARED_COUNTS
        /* One work-item: bins of 16 values at once (the same rule in vector form: the positions are
         * clamped to >= 0, where truncation is floor), then plain increments; 2.3x faster on PoCL. */
        for (; c + 16 <= cols; c += 16) {
            float16 v = RELATIVE16(vload16(0, row + c));
            int16 b = convert_int16(fmin(fmax((v * prescale - lo_scaled) * scale, 0.0f), last));
            int lanes[16];
            vstore16(v >= lo && v <= hi ? b : -1, 0, lanes);
            for (int j = 0; j < 16; j++)
                if (lanes[j] >= 0) counts[lanes[j]]++;
        }
#endif
        for (; c < cols; c += size) {
            float v = RELATIVE(row[c]);
            if (v >= lo && v <= hi) {
                int b = (int)fmin(fmax((v * prescale - lo_scaled) * scale, 0.0f), last);
#if SHARED_COUNTS
                atomic_inc(&counts[b]);
#else
                counts[b]++;
#endif
            }
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int b = lid; b < bins; b += size) {
        if (accumulate) {
            if (counts[b]) atomic_add(&out[b], counts[b]);
        } else {
            out[g * bins + b] = counts[b];
        }
    }
}
