/* edges.cl: Canny's detector and zero crossings, seed section "Edge detection". One work-item per pixel
 * (per CM processor) except the threshold rule, which runs one work-item per histogram (per tile).
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
 * Defines: INTERPOLATE (1: the gradient magnitude is interpolated between the two neighbours on each
 * side, 0: the nearest of the 8 directions), LOCAL (1: thresholds per tile, interpolated between tile
 * centres; 0: one pair), CLEAR_MARKS (1: nms_classify also zeroes the marks of the labelling path),
 * WITH_DIRECTION (1: gradient also writes the direction).
 */
#include "vmcl.h"

#ifndef INTERPOLATE
#define INTERPOLATE 1
#endif
#ifndef LOCAL
#define LOCAL 0
#endif
#ifndef CLEAR_MARKS
#define CLEAR_MARKS 0
#endif
#ifndef WITH_DIRECTION
#define WITH_DIRECTION 0
#endif

#define AT(f, xx, yy) ((f)[(yy) * W + (xx)])
#define WEAK 1
#define STRONG 3

/* Sobel derivatives at (x, y), borders clamped: gx along x (columns), gy along y (rows, downwards). */
inline float2 sobel(__global const float *s, long x, long y, long W, long H)
{
    long xl = max(x - 1, 0L), xr = min(x + 1, W - 1), yu = max(y - 1, 0L), yd = min(y + 1, H - 1);
    float gx = (AT(s, xr, yu) + 2.0f * AT(s, xr, y) + AT(s, xr, yd))
             - (AT(s, xl, yu) + 2.0f * AT(s, xl, y) + AT(s, xl, yd));
    float gy = (AT(s, xl, yd) + 2.0f * AT(s, x, yd) + AT(s, xr, yd))
             - (AT(s, xl, yu) + 2.0f * AT(s, x, yu) + AT(s, xr, yu));
    return (float2)(gx, gy);
}

__kernel void gradient(__global const float *smoothed, __global float *magnitude, __global float *direction,
                       long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float2 g = sobel(smoothed, x, y, W, H);
    magnitude[y * W + x] = sqrt(g.x * g.x + g.y * g.y);
#if WITH_DIRECTION
    direction[y * W + x] = atan2(g.y, g.x);
#endif
}

/* The (low, high) pair that applies at (x, y): one pair, or bilinear between the centres of TILE x TILE
 * tiles (clamped beyond the outer centres), so thresholds change smoothly from tile to tile. */
inline float2 thresholds_at(__global const float *thr, long x, long y, long tile, long tiles_x, long tiles_y)
{
#if LOCAL
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
#else
    return (float2)(thr[0], thr[1]);
#endif
}

#if INTERPOLATE
/* Is m at least the magnitude interpolated at both neighbours along the gradient? The gradient direction
 * falls between an axis neighbour (weight 1 - w) and a diagonal one (weight w) on each side; the case
 * split and the ties (<=) follow scikit-image's bilinear suppression so both keep the same pixels. */
inline int is_maximum(__global const float *M, float m, float gx, float gy, long x, long y, long W)
{
    float ax = fabs(gx), ay = fabs(gy), w, plus, minus;
    if ((gy > 0.0f) == (gx > 0.0f)) {
        if (ay > ax) {
            w = ax / ay;
            plus = AT(M, x + 1, y + 1) * w + AT(M, x, y + 1) * (1.0f - w);
            minus = AT(M, x - 1, y - 1) * w + AT(M, x, y - 1) * (1.0f - w);
        } else {
            w = ay / ax;
            plus = AT(M, x + 1, y + 1) * w + AT(M, x + 1, y) * (1.0f - w);
            minus = AT(M, x - 1, y - 1) * w + AT(M, x - 1, y) * (1.0f - w);
        }
    } else {
        if (ay < ax) {
            w = ay / ax;
            plus = AT(M, x + 1, y - 1) * w + AT(M, x + 1, y) * (1.0f - w);
            minus = AT(M, x - 1, y + 1) * w + AT(M, x - 1, y) * (1.0f - w);
        } else {
            w = ax / ay;
            plus = AT(M, x + 1, y - 1) * w + AT(M, x, y - 1) * (1.0f - w);
            minus = AT(M, x - 1, y + 1) * w + AT(M, x, y + 1) * (1.0f - w);
        }
    }
    return plus <= m && minus <= m;
}
#else
/* Without interpolation: the neighbours of the nearest of the four axes and diagonals (sectors of 45
 * degrees around each), compared directly, "it may not be crucial to use interpolation". */
inline int is_maximum(__global const float *M, float m, float gx, float gy, long x, long y, long W)
{
    const float tan22 = 0.41421356f;
    float ax = fabs(gx), ay = fabs(gy);
    long dx, dy;
    if (ay <= tan22 * ax) {
        dx = 1; dy = 0;
    } else if (ax <= tan22 * ay) {
        dx = 0; dy = 1;
    } else {
        dx = 1; dy = (gx > 0.0f) == (gy > 0.0f) ? 1 : -1;
    }
    return AT(M, x + dx, y + dy) <= m && AT(M, x - dx, y - dy) <= m;
}
#endif

/* State of every pixel: 3 strong (a maximum at or above high), 1 weak (a maximum at or above low and
 * above 0), 0 otherwise; the outermost ring is 0, its neighbours lying outside the image. Bit 0 is the
 * mask that gets labelled, and every non-zero state has it: the labeller combines mask bytes with
 * bitwise operators, so 1 and 2 would not count as touching. */
__kernel void nms_classify(__global const float *smoothed, __global const float *magnitude,
                           __global const float *thr, __global uchar *state, __global uchar *marks,
                           long tile, long tiles_x, long tiles_y, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
#if CLEAR_MARKS
    marks[i] = 0;
#endif
    uchar c = 0;
    if (x > 0 && y > 0 && x + 1 < W && y + 1 < H) {
        float m = magnitude[i];
        float2 t = thresholds_at(thr, x, y, tile, tiles_x, tiles_y);
        if (m >= t.x && m > 0.0f) {
            float2 g = sobel(smoothed, x, y, W, H);
            if (is_maximum(magnitude, m, g.x, g.y, x, y, W)) c = m >= t.y ? STRONG : WEAK;
        }
    }
    state[i] = c;
}

/* The state of a field under two thresholds, for hysteresis on its own (NaN counts as below both). */
__kernel void double_threshold(__global const float *v, __global uchar *state, __global uchar *marks,
                               float low, float high, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float value = v[i];
    marks[i] = 0;
    state[i] = value >= high ? STRONG : (value >= low ? WEAK : 0);
}

/* Every strong pixel tells its component's principal (label = the largest address in the component)
 * that the component holds a strong pixel: the router's send with "or", where every message is 1, so
 * concurrent stores of the same value need neither buckets nor atomics. */
__kernel void mark_strong(__global const uchar *state, __global const int *label, __global uchar *marks, long n)
{
    long i = get_global_id(0);
    if (i < n && state[i] == STRONG) marks[label[i]] = 1;
}

/* Every pixel reads its principal's mark (the router's get). */
__kernel void keep_marked(__global const int *label, __global const uchar *marks, __global uchar *edges, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int l = label[i];
    edges[i] = l >= 0 ? marks[l] : 0;
}

/* One synchronous step of spreading activation: a weak pixel next to an edge pixel (8-neighbours)
 * becomes an edge pixel. `changed` is set (a plain store of 1) when any pixel did. */
__kernel void grow_step(__global const uchar *in, __global uchar *out, __global int *changed, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    uchar c = in[i];
    if (c == WEAK) {
        long xl = max(x - 1, 0L), xr = min(x + 1, W - 1), yu = max(y - 1, 0L), yd = min(y + 1, H - 1);
        for (long yy = yu; yy <= yd && c == WEAK; yy++)
            for (long xx = xl; xx <= xr; xx++)
                if (AT(in, xx, yy) == STRONG) { c = STRONG; break; }
        if (c == STRONG) *changed = 1;
    }
    out[i] = c;
}

__kernel void strong_pixels(__global const uchar *state, __global uchar *edges, long n)
{
    long i = get_global_id(0);
    if (i < n) edges[i] = state[i] == STRONG;
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

__kernel void histogram_thresholds(__global const int *hist, __global float *thr, int bins, float lo,
                                   float width, float4 rule, long tiles)
{
    long t = get_global_id(0);
    if (t >= tiles) return;
    __global const int *h = hist + t * bins;
    long total = 0;
    for (int b = 0; b < bins; b++) total += h[b];
    thr[2 * t] = rule.z * quantile(h, bins, total, rule.x, lo, width);
    thr[2 * t + 1] = rule.w * quantile(h, bins, total, rule.y, lo, width);
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
inline int nearer_side(float c, float q)
{
    int opposite = (c > 0.0f && q < 0.0f) || (c < 0.0f && q > 0.0f);
    return opposite && (fabs(c) < fabs(q) || (fabs(c) == fabs(q) && c > 0.0f));
}

__kernel void zero_crossings(__global const float *f, __global uchar *mask, __global char *sign,
                             __global float *slope, float min_slope, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float c = f[i];
    float l = AT(f, max(x - 1, 0L), y), r = AT(f, min(x + 1, W - 1), y);
    float u = AT(f, x, max(y - 1, 0L)), d = AT(f, x, min(y + 1, H - 1));
    int crossing;
    if (c == 0.0f)
        crossing = (l > 0.0f && r < 0.0f) || (l < 0.0f && r > 0.0f) || (u > 0.0f && d < 0.0f)
                   || (u < 0.0f && d > 0.0f);
    else
        crossing = nearer_side(c, l) || nearer_side(c, r) || nearer_side(c, u) || nearer_side(c, d);
    float dx = 0.5f * (r - l), dy = 0.5f * (d - u);
    float s = sqrt(dx * dx + dy * dy);
    int keep = crossing && s >= min_slope;
    mask[i] = keep;
    slope[i] = keep ? s : 0.0f;
    sign[i] = keep ? (dx < 0.0f ? 1 : (dx > 0.0f ? -1 : 0)) : 0;
}
