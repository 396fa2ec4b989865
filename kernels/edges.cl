/* edges.cl: Canny's detector and zero crossings, seed section "Edge detection".
 *
 *   gradient            directional derivatives of the smoothed image (Sobel) and their magnitude
 *   nms_classify        non-maximum suppression fused with the double threshold: 0 none, 1 weak, 3 strong
 *   double_threshold    the same states for any field (hysteresis on its own)
 *   mark_strong,        hysteresis after labelling the weak-or-strong mask (distance doubling): strong
 *   keep_marked         pixels mark their component's principal, then every pixel reads its mark
 *   grow_step,          hysteresis by the paper's O(m) spreading activation
 *   strong_pixels
 *   histogram_thresholds  quantiles of gradient-magnitude histograms (the noise estimate)
 *   zero_crossings      sign changes of a Laplacian-of-Gaussian field between 4-neighbours
 *
 * As in early_filters.cl, work-item (k, y) stands for the VEC pixels [k * VEC, (k + 1) * VEC) of row y (16 on
 * CPUs, 1 on GPUs): one vector step inside the image, pixel by pixel where the 3 x 3 window meets a
 * border. Each per-pixel rule is written once as a macro over the operand type, so the vector and the
 * border paths compute the same operations in the same order; the ?: and comparison operators act per
 * lane on vectors.
 *
 * Defines: VEC (1|16). nms_classify's switches are arguments, not defines (the file is then one build
 * on a first run): interpolate (1: the gradient magnitude is interpolated between the two neighbours on
 * each side, 0: the nearest of the 8 directions); per_tile (1: thresholds per tile, interpolated between
 * tile centres; 0: one pair); clear_marks (1: also zero the marks of the labelling path).
 */
#define T float
#include "vmcl.h"
#include "angles.h"


#if VEC == 1
#define VUCHAR uchar
#define VCHAR char
#define ANY(v) (v)
#else
#define VUCHAR VCAT(uchar, VEC)
#define VCHAR VCAT(char, VEC)
#define ANY(v) any(v)
#endif
#define TO_VUCHAR(v) VCAT(convert_, VUCHAR)(v)
#define TO_VCHAR(v) VCAT(convert_, VCHAR)(v)

#define WEAK 1
#define STRONG 3

/* Rows y-1, y, y+1 (clamped) of a field, and whether the VEC pixels from x0 have both x-neighbours. */
#define ROWS(f, type)                                                                      \
    __global const type *f##_u = f + max(y - 1, 0L) * W;                                   \
    __global const type *f##_m = f + y * W;                                                \
    __global const type *f##_d = f + min(y + 1, H - 1) * W;
#define INTERIOR (x0 >= 1 && x0 + VEC + 1 <= W)
/* Neighbour (dx, dy) of the VEC pixels from x0 (vector path), or of pixel x, clamped (border path). */
#define NV(f, dx, dy) VLOAD((dy) < 0 ? f##_u + x0 + (dx) : (dy) > 0 ? f##_d + x0 + (dx) : f##_m + x0 + (dx))
#define NS(f, dx, dy) ((dy) < 0 ? f##_u : (dy) > 0 ? f##_d : f##_m)[clamp(x + (dx), 0L, W - 1)]

/* Sobel derivatives: gx along x (columns), gy along y (rows, downwards). */
#define SOBEL_X(N) ((N(1, -1) + 2.0f * N(1, 0) + N(1, 1)) - (N(-1, -1) + 2.0f * N(-1, 0) + N(-1, 1)))
#define SOBEL_Y(N) ((N(-1, 1) + 2.0f * N(0, 1) + N(1, 1)) - (N(-1, -1) + 2.0f * N(0, -1) + N(1, -1)))

#define SV(dx, dy) NV(s, dx, dy)
#define SS(dx, dy) NS(s, dx, dy)

/* sqrt(gx^2 + gy^2) over float32's whole range. Where the larger component lies outside
 * [2^-50, 2^50] (and is not 0), the squares could overflow or underflow, so both components are scaled
 * by the power of two that brings it near 1, which is exact, and the result is scaled back: magnitudes
 * are then float32's at any image scale. Other lanes keep the plain expression, bit for bit, and it is
 * all that runs unless some lane needs the scaling. Defined for (VT, VIT) and (float, int). */
#define DEFINE_MAGNITUDE(NAME, F, I)                                                       \
    __attribute__((always_inline)) inline F NAME(F gx, F gy)                               \
    {                                                                                      \
        F plain = sqrt(gx * gx + gy * gy), big = fmax(fabs(gx), fabs(gy));                 \
        /* -1 where true, for any() on a scalar as on a vector (which test the top bit). */ \
        I rescale = (big > 0x1p50f || big < 0x1p-50f) && big > 0.0f ? (I)-1 : (I)0;        \
        if (!ANY(rescale)) return plain;                                                   \
        I e = rescale ? clamp(ilogb(big), -149, 127) : (I)0;                               \
        F sx = ldexp(gx, -e), sy = ldexp(gy, -e);                                          \
        return rescale ? ldexp(sqrt(sx * sx + sy * sy), e) : plain;                        \
    }
DEFINE_MAGNITUDE(magnitude_v, VT, VIT)
DEFINE_MAGNITUDE(magnitude_s, float, int)

DEFINE_ATAN2(direction_v, VT, VIT)
DEFINE_ATAN2(direction_s, float, int)

/* with_direction: also write the gradient's direction. An argument, not a define, so that gradient
 * shares the build of the file's other define-free kernels (one program fewer on a first run). */
__kernel void gradient(__global const float *s, __global float *magnitude, __global float *direction,
                       long W, long H, int with_direction)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    ROWS(s, float)
    if (INTERIOR) {
        VT gx = SOBEL_X(SV), gy = SOBEL_Y(SV);
        VSTORE(magnitude_v(gx, gy), magnitude + y * W + x0);
        if (with_direction)
            VSTORE(direction_v(gy, gx), direction + y * W + x0);
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float gx = SOBEL_X(SS), gy = SOBEL_Y(SS);
        magnitude[y * W + x] = magnitude_s(gx, gy);
        if (with_direction)
            direction[y * W + x] = direction_s(gy, gx);
    }
}

/* The (low, high) pair that applies at (x, y): one pair, or bilinear between the centres of tile x tile
 * tiles (clamped beyond the outer centres), so thresholds change smoothly from tile to tile. */
inline float2 thresholds_at(__global const float *thr, int per_tile, long x, long y, long tile, long tiles_x,
                            long tiles_y)
{
    if (!per_tile)
        return (float2)(thr[0], thr[1]);
    float centre = 0.5f * (float)(tile - 1);
    float fx = clamp(((float)x - centre) / (float)tile, 0.0f, (float)(tiles_x - 1));
    float fy = clamp(((float)y - centre) / (float)tile, 0.0f, (float)(tiles_y - 1));
    long x0 = (long)fx, y0 = (long)fy;
    long x1 = min(x0 + 1, tiles_x - 1), y1 = min(y0 + 1, tiles_y - 1);
    float ax = fx - (float)x0, ay = fy - (float)y0;
    __global const float2 *t = (__global const float2 *)thr;
    float2 top = (1.0f - ax) * t[y0 * tiles_x + x0] + ax * t[y0 * tiles_x + x1];
    float2 bottom = (1.0f - ax) * t[y1 * tiles_x + x0] + ax * t[y1 * tiles_x + x1];
    return (1.0f - ay) * top + ay * bottom;
}

/* Non-maximum suppression: is m at least the magnitude on both sides along the gradient (ties kept)?
 * With interpolation the gradient falls between an axis neighbour (weight 1 - w) and a diagonal one
 * (weight w) on each side; the case split and ties follow scikit-image's bilinear rule, so both keep the
 * same pixels. Without, the two neighbours of the nearest of the 4 axes and diagonals (sectors of 45
 * degrees) are compared directly: "it may not be crucial to use interpolation". n_<dx><dy> is the
 * magnitude at neighbour (dx, dy), m standing for -1 and p for +1. Defined for the float vector (F, I)
 * = (VT, VIT) and for float (float, int). */
#define DEFINE_IS_MAXIMUM_INTERPOLATED(NAME, F, I)                                         \
    __attribute__((always_inline)) inline I NAME(F m, F gx, F gy, F n_mm, F n_0m, F n_pm, F n_m0, F n_p0, F n_mp, F n_0p, F n_pp) \
    {                                                                                      \
        F ax = fabs(gx), ay = fabs(gy);                                                    \
        I same = (gy > 0.0f) == (gx > 0.0f);                                               \
        I ymajor = same ? ay > ax : ay >= ax;                                              \
        F w = min(ax, ay) / max(ax, ay); /* the minor over the major component */         \
        F diag_plus = same ? n_pp : n_pm, diag_minus = same ? n_mm : n_mp;                 \
        F axis_plus = ymajor ? (same ? n_0p : n_0m) : n_p0;                                \
        F axis_minus = ymajor ? (same ? n_0m : n_0p) : n_m0;                               \
        return (diag_plus * w + axis_plus * (1.0f - w) <= m) && (diag_minus * w + axis_minus * (1.0f - w) <= m); \
    }
#define DEFINE_IS_MAXIMUM_NEAREST(NAME, F, I)                                              \
    __attribute__((always_inline)) inline I NAME(F m, F gx, F gy, F n_mm, F n_0m, F n_pm, F n_m0, F n_p0, F n_mp, F n_0p, F n_pp) \
    {                                                                                      \
        const float tan22 = 0.41421356f;                                                   \
        F ax = fabs(gx), ay = fabs(gy);                                                    \
        I horizontal = ay <= tan22 * ax;                                                   \
        I vertical = !horizontal && ax <= tan22 * ay;                                      \
        I same = (gy > 0.0f) == (gx > 0.0f);                                               \
        F plus = horizontal ? n_p0 : vertical ? n_0p : same ? n_pp : n_pm;                 \
        F minus = horizontal ? n_m0 : vertical ? n_0m : same ? n_mm : n_mp;                \
        return plus <= m && minus <= m;                                                    \
    }
DEFINE_IS_MAXIMUM_INTERPOLATED(interpolated_maximum_v, VT, VIT)
DEFINE_IS_MAXIMUM_INTERPOLATED(interpolated_maximum_s, float, int)
DEFINE_IS_MAXIMUM_NEAREST(nearest_maximum_v, VT, VIT)
DEFINE_IS_MAXIMUM_NEAREST(nearest_maximum_s, float, int)
#define NEIGHBOURS(M) M(-1, -1), M(0, -1), M(1, -1), M(-1, 0), M(1, 0), M(-1, 1), M(0, 1), M(1, 1)

/* State: 3 strong (a maximum at or above high), 1 weak (a maximum at or above low and above 0), 0
 * otherwise. Bit 0 is the mask that gets labelled, and every non-zero state has it: the labeller
 * combines mask bytes with bitwise operators, so 1 and 2 would not count as touching. */
#define CLASSIFY(I, keep, m, low, high) \
    ((keep) && (m) >= (low) && (m) > 0.0f ? ((m) >= (high) ? (I)STRONG : (I)WEAK) : (I)0)

#define MV(dx, dy) NV(mag, dx, dy)
#define MS(dx, dy) NS(mag, dx, dy)

/* The outermost ring of pixels is 0: their neighbours lie outside the image. */
__kernel void nms_classify(__global const float *s, __global const float *mag, __global const float *thr,
                           __global uchar *state, __global uchar *marks, long tile, long tiles_x, long tiles_y,
                           long W, long H, int interpolate, int per_tile, int clear_marks)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    long i0 = y * W + x0;
    if (clear_marks)
        for (long x = x0; x < min(x0 + VEC, W); x++) marks[y * W + x] = 0;
    ROWS(s, float)
    ROWS(mag, float)
    int inner_row = y > 0 && y + 1 < H;
    if (INTERIOR && inner_row) {
        VT m = VLOAD(mag + i0), gx = SOBEL_X(SV), gy = SOBEL_Y(SV);
        VT low = (VT)thr[0], high = (VT)thr[1];
        if (per_tile) {
            float lows[VEC], highs[VEC];
            for (int j = 0; j < VEC; j++) {
                float2 t = thresholds_at(thr, per_tile, x0 + j, y, tile, tiles_x, tiles_y);
                lows[j] = t.x;
                highs[j] = t.y;
            }
            low = VLOAD(lows);
            high = VLOAD(highs);
        }
        VIT keep = interpolate ? interpolated_maximum_v(m, gx, gy, NEIGHBOURS(MV))
                               : nearest_maximum_v(m, gx, gy, NEIGHBOURS(MV));
        VSTORE(TO_VUCHAR(CLASSIFY(VIT, keep, m, low, high)), state + i0);
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        uchar c = 0;
        if (inner_row && x > 0 && x + 1 < W) {
            float m = mag[y * W + x], gx = SOBEL_X(SS), gy = SOBEL_Y(SS);
            float2 t = thresholds_at(thr, per_tile, x, y, tile, tiles_x, tiles_y);
            int keep = interpolate ? interpolated_maximum_s(m, gx, gy, NEIGHBOURS(MS))
                                   : nearest_maximum_s(m, gx, gy, NEIGHBOURS(MS));
            c = CLASSIFY(int, keep, m, t.x, t.y);
        }
        state[y * W + x] = c;
    }
}

/* The states of any field under two thresholds, for hysteresis on its own (NaN counts as below both). */
__kernel void double_threshold(__global const float *v, __global uchar *state, __global uchar *marks,
                               float low, float high, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float value = v[y * W + x];
        marks[y * W + x] = 0;
        state[y * W + x] = value >= high ? STRONG : (value >= low ? WEAK : 0);
    }
}

/* Every strong pixel tells its component's principal (label = the largest address in the component)
 * that the component holds a strong pixel: the router's send with "or", where every message is 1, so
 * concurrent stores of the same value need neither buckets nor atomics. */
__kernel void mark_strong(__global const uchar *state, __global const int *label, __global uchar *marks, long n)
{
    long i0 = get_global_id(0) * VEC;
#if VEC > 1
    /* Strong pixels are few: most chunks are done after one vector compare. */
    if (i0 + VEC <= n && !any(VLOAD(state + i0) == (VUCHAR)STRONG)) return;
#endif
    for (long i = i0; i < min(i0 + VEC, n); i++)
        if (state[i] == STRONG) marks[label[i]] = 1;
}

/* Every pixel reads its principal's mark (the router's get). */
__kernel void keep_marked(__global const int *label, __global const uchar *marks, __global uchar *edges, long n)
{
    long i0 = get_global_id(0) * VEC;
#if VEC > 1
    if (i0 + VEC <= n && !any(VLOAD(label + i0) >= 0)) {
        VSTORE((VUCHAR)0, edges + i0);
        return;
    }
#endif
    for (long i = i0; i < min(i0 + VEC, n); i++) {
        int l = label[i];
        edges[i] = l >= 0 ? marks[l] : 0;
    }
}

/* One synchronous step of spreading activation: a weak pixel next to an edge pixel (8-neighbours)
 * becomes an edge pixel; `changed` is set (a plain store of 1) when any pixel did. Off the image the
 * neighbours repeat the edge pixels, which adds no edge pixel that is not already a neighbour. */
#define IS_STRONG(v) ((v) == (uchar)STRONG)
#define GROWN(N, c)                                                                        \
    ((c) == (uchar)WEAK && (IS_STRONG(N(-1, -1)) || IS_STRONG(N(0, -1)) || IS_STRONG(N(1, -1)) \
                            || IS_STRONG(N(-1, 0)) || IS_STRONG(N(1, 0)) || IS_STRONG(N(-1, 1)) \
                            || IS_STRONG(N(0, 1)) || IS_STRONG(N(1, 1))))
#define GV(dx, dy) NV(in, dx, dy)
#define GS(dx, dy) NS(in, dx, dy)

__kernel void grow_step(__global const uchar *in, __global uchar *out, __global int *changed, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    ROWS(in, uchar)
    if (INTERIOR) {
        VUCHAR c = VLOAD(in_m + x0);
        VCHAR grown = GROWN(GV, c);
        VSTORE(grown ? (VUCHAR)STRONG : c, out + y * W + x0);
        if (ANY(grown)) *changed = 1;
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        uchar c = in_m[x];
        int grown = GROWN(GS, c);
        out[y * W + x] = grown ? STRONG : c;
        if (grown) *changed = 1;
    }
}

__kernel void strong_pixels(__global const uchar *state, __global uchar *edges, long n)
{
    long i0 = get_global_id(0) * VEC;
    for (long i = i0; i < min(i0 + VEC, n); i++) edges[i] = state[i] == STRONG;
}

/* One work-item per histogram (tile): thresholds (rule.z * q(rule.x), rule.w * q(rule.y)), where q(f) is
 * the f-quantile of the counted values, np.percentile's order statistic f * (N - 1) with the values of
 * a bin spread evenly across it. Bin b covers [lo + b * width, lo + (b + 1) * width). */
inline float quantile(__global const int *h, int bins, long total, float f, float lo, float width)
{
    if (total == 0) return lo;
    float p = f * (float)(total - 1);
    long below = 0;
    for (int b = 0; b < bins; b++) {
        if (h[b] > 0 && (float)(below + h[b]) > p)
            return lo + ((float)b + (p - (float)below + 0.5f) / (float)h[b]) * width;
        below += h[b];
    }
    return lo + (float)bins * width;
}

/* The histograms span [0, top] (from the field's maximum on the device, [0, 1] for a field of zeros:
 * vmcl.cm.reduce.histogram_to_top), bins of width top / bins. When that width is below float32's
 * normal range (a subnormal top), the quantiles are computed in units a power of two smaller, exactly,
 * and scaled back once at the end, so they keep the precision float32 has at that scale. */
__kernel void histogram_thresholds(__global const int *hist, __global float *thr, int bins,
                                   __global const float *top, float4 rule, long tiles)
{
    long t = get_global_id(0);
    if (t >= tiles) return;
    float range = top[0] > 0.0f ? top[0] : 1.0f, lo = 0.0f, width = range / (float)bins, unscale = 1.0f;
    if (width < FLT_MIN) {
        float prescale = ldexp(1.0f, min(-ilogb(range), 127));
        width = range * prescale / (float)bins;
        unscale = 1.0f / prescale;
    }
    __global const int *h = hist + t * bins;
    long total = 0;
    for (int b = 0; b < bins; b++) total += h[b];
    thr[2 * t] = rule.z * quantile(h, bins, total, rule.x, lo, width) * unscale;
    thr[2 * t + 1] = rule.w * quantile(h, bins, total, rule.y, lo, width) * unscale;
}

__kernel void set_thresholds(__global float *thr, float low, float high)
{
    thr[0] = low;
    thr[1] = high;
}

/* A zero crossing lies between 4-neighbours of strictly opposite signs; of the two pixels, the one
 * nearer zero (the positive one on a tie) is marked, so a crossing is one pixel thick and within half a
 * pixel of the linearly interpolated crossing. A pixel that is exactly zero is marked when its left and
 * right (or upper and lower) neighbours have opposite signs; flat runs of exact zeros mark nothing.
 * slope is the gradient magnitude of the field (central differences); sign is the brightness polarity
 * across the crossing along x (the field has the sign of the Laplacian, which falls where brightness
 * rises): +1 dark to bright going right, -1 bright to dark, 0 for a crossing with no x component. */
#define OPPOSITE(a, b) (((a) > 0.0f && (b) < 0.0f) || ((a) < 0.0f && (b) > 0.0f))
#define NEARER(c, q) (OPPOSITE(c, q) && (fabs(c) < fabs(q) || (fabs(c) == fabs(q) && (c) > 0.0f)))
#define CROSSING(c, l, r, u, d)                                                            \
    ((c) == 0.0f ? OPPOSITE(l, r) || OPPOSITE(u, d)                                        \
                 : NEARER(c, l) || NEARER(c, r) || NEARER(c, u) || NEARER(c, d))

#define FV(dx, dy) NV(f, dx, dy)
#define FS(dx, dy) NS(f, dx, dy)

__kernel void zero_crossings(__global const float *f, __global uchar *mask, __global char *sign,
                             __global float *slope, float min_slope, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    ROWS(f, float)
    if (INTERIOR) {
        VT c = FV(0, 0), l = FV(-1, 0), r = FV(1, 0), u = FV(0, -1), d = FV(0, 1);
        VT dx = 0.5f * (r - l), dy = 0.5f * (d - u);
        VT s = magnitude_v(dx, dy);
        VIT keep = CROSSING(c, l, r, u, d) && s >= min_slope;
        long i0 = y * W + x0;
        VSTORE(TO_VUCHAR(keep ? (VIT)1 : (VIT)0), mask + i0);
        VSTORE(keep ? s : (VT)0.0f, slope + i0);
        VSTORE(TO_VCHAR(keep ? (dx < 0.0f ? (VIT)1 : dx > 0.0f ? (VIT)-1 : (VIT)0) : (VIT)0), sign + i0);
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float c = FS(0, 0), l = FS(-1, 0), r = FS(1, 0), u = FS(0, -1), d = FS(0, 1);
        float dx = 0.5f * (r - l), dy = 0.5f * (d - u);
        float s = magnitude_s(dx, dy);
        int keep = CROSSING(c, l, r, u, d) && s >= min_slope;
        mask[y * W + x] = keep;
        slope[y * W + x] = keep ? s : 0.0f;
        sign[y * W + x] = keep ? (dx < 0.0f ? 1 : (dx > 0.0f ? -1 : 0)) : 0;
    }
}
