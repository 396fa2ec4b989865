/* motion.cl: optical flow by patchwise comparison over a range of displacements, seed section "Motion"
 * (Bulthoff, Little and Poggio).
 *
 *   cost          the pointwise comparison of frame 0 at (x, y) with frame 1 at (x + vx, y + vy), for a
 *                 batch of displacements: one row of them, or all
 *   vote_running  the paper's "non-maximum suppression across velocities" done during the iteration
 *                 over displacements: each pixel's winner is updated by one row of vote planes (fixed
 *                 vy) at a time, so no table over all displacements exists (three rows at most)
 *   winner_table  the same suppression over the full table of votes (the faithful variant); both run
 *                 visit_row, so they agree bit for bit
 *   moments       the fields whose box sums normalise the winning vote
 *   finish        winner -> flow (with the sub-pixel parabola), normalised score, discontinuity mask
 *   decimate, flow_planes, mean_flow, warp   the coarse-to-fine pyramid: half-size images, the coarse
 *                 flow averaged over the patch, and frame 1's features warped by it, doubled, so that
 *                 the finer search is for the residual
 *   sign_agreement      +1 where two fields have the same sign, -1 elsewhere (the sign-correlation theorem)
 *
 * The patch sums themselves are vmcl.cm.scan.box_sum's grid-scans over stacks of vote planes.
 *
 * Work-item (k, y) of cost, vote_running, winner_table stands for the VEC processors (pixels)
 * [col0 + k VEC, col0 + (k + 1) VEC) of row y: VEC = 16 on CPUs, whose SIMD lanes then see contiguous
 * loads, 1 on GPUs; the host launches the width's remainder with VEC = 1.
 *
 * Displacement index d = (vy + delta) n + (vx + delta), n = 2 delta + 1 (vy major). The winner minimises
 * a key (see KEY); nothing depends on the work-group size. Frame 1 is read with clamped coordinates (the
 * edge pixel repeats), so every displacement has a vote at every pixel.
 *
 * Defines: F_T (float|uchar), the feature type; V_T (float|int), the vote type; COMPARE: 0 squared
 * difference (brightness, LoG), 1 disagreement of signs (sign of the LoG), 2 XOR of binary maps (edges);
 * VEC, as above.
 */
#include "vmcl.h"

#ifndef F_T
#define F_T float
#endif
#ifndef V_T
#define V_T float
#endif
#ifndef COMPARE
#define COMPARE 0
#endif

#define CMP_SQUARED 0
#define CMP_SIGN 1
#define CMP_XOR 2

#if COMPARE == CMP_SQUARED
#define V_HIGHEST INFINITY
#else
#define V_HIGHEST INT_MAX
#endif
#define NONE INFINITY

/* Vectors of VEC (1 or 16) features, votes, floats and ints; masks are IV (all bits set = true for
 * VEC = 16, 1 for VEC = 1: select() and the ANY below read both). */
#if VEC == 1
#define FV F_T
#define VV V_T
#define FLV float
#define IV int
#define ANY(m) (m)
#define LANES 0
#else
#define FV VCAT(F_T, VEC)
#define VV VCAT(V_T, VEC)
#define FLV VCAT(float, VEC)
#define IV VCAT(int, VEC)
#define ANY(m) any(m)
#define LANES ((int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
#endif
#define TO_VV(v) VCAT(convert_, VV)(v)
#define TO_FLV(v) VCAT(convert_, FLV)(v)

inline VV compare(FV a, FV b)
{
#if COMPARE == CMP_SQUARED
    FV e = a - b;
    return e * e;
#elif COMPARE == CMP_SIGN
    return TO_VV((a >= (FV)0) != (b >= (FV)0)) & 1;
#else
    return TO_VV((a != (FV)0) != (b != (FV)0)) & 1;
#endif
}

/* Frame 1's features at (x0 + l + vx, y + vy) for the VEC lanes, clamped to the field: one vector load
 * where the row segment lies inside, lane by lane where it meets a border. */
inline FV shifted(__global const F_T *f1, long x0, long y, int vx, int vy, long W, long H)
{
    long y1 = clamp(y + vy, 0L, H - 1), x1 = x0 + vx;
    __global const F_T *row = f1 + y1 * W;
    if (x1 >= 0 && x1 + VEC <= W) return VLOAD(row + x1);
    F_T lanes[VEC];
    for (int l = 0; l < VEC; l++) lanes[l] = row[clamp(x1 + l, 0L, W - 1)];
    return VLOAD(lanes);
}

/* Plane p of `out` holds displacement d0 + p. */
__kernel void cost(__global const F_T *f0, __global const F_T *f1, __global V_T *out, long W, long H, long col0,
                   long count, int delta, int d0, int planes)
{
    long k = get_global_id(0), y = get_global_id(1);
    if (k >= count || y >= H) return;
    long x0 = col0 + k * VEC;
    size_t i = y * W + x0, plane = W * H;
    int n = 2 * delta + 1;
    FV a = VLOAD(f0 + i);
    for (int p = 0; p < planes; p++) {
        int d = d0 + p;
        FV b = shifted(f1, x0, y, d % n - delta, d / n - delta, W, H);
        VSTORE(compare(a, b), out + p * plane + i);
    }
}

/* Pixels in the window of radius r around (x, y): box_sum counts zero outside the field. */
inline FLV window_count(IV x, long y, long W, long H, int r)
{
    IV w = min(x + r, (IV)(W - 1)) - max(x - r, (IV)0) + 1;
    return TO_FLV(w) * (float)(min(y + r, H - 1) - max(y - r, 0L) + 1);
}

/* Patch contrast sum (f - mean)^2 from the box sums of f and f^2; rounding can take it below zero. */
inline FLV contrast(FLV sum, FLV sum2, FLV count)
{
    return max(sum2 - sum * sum / count, (FLV)0.0f);
}

/* The slow-motion prior of the squared differences: each vote gains penalty * C0 * |v|^2, with C0 frame
 * 0's patch contrast so that the prior follows the features' units. It settles the aperture problem (a
 * patch of one orientation, whose votes along it differ only by rounding) on the slowest candidate.
 * Binary votes are exact integers whose ties the tie rule settles, and take none. */
inline FLV slowness(__global const float *moments, float penalty, long x0, long y, long W, long H, int r)
{
#if COMPARE == CMP_SQUARED
    size_t i = y * W + x0;
    FLV count = window_count((IV)(int)x0 + LANES, y, W, H, r);
    return penalty * contrast(VLOAD(moments + i), VLOAD(moments + W * H + i), count);
#else
    return (FLV)0.0f;
#endif
}

/* The key each winner minimises; equal keys go to the first displacement visited (rows out from vy = 0,
 * see row_of; vx ascending within a row). Squared differences: the penalised vote (equal keys need equal
 * sums of squared differences, in practice a flat patch, which has no estimate). Binary votes:
 * vote * (2 delta^2 + 1) + |v|^2, exact integers, so ties go to the smaller |v|^2 first. One comparison
 * per displacement either way: a second one for ties doubled the time of the whole update on PoCL. */
#if COMPARE == CMP_SQUARED
#define KEY(v, norm) ((v) + slow * (float)(norm))
#else
#define KEY(v, norm) ((v) * (2 * delta * delta + 1) + (norm))
#endif

/* What the parabola is fitted to: the penalised votes, whose minimum the winner is; binary votes as they
 * are (their keys' tie-break term would bend the parabola). */
#if COMPARE == CMP_SQUARED
#define FIT(raw, key) (key)
#else
#define FIT(raw, key) TO_FLV(raw)
#endif

/* Each pixel's winner so far: its key and displacement index. */
typedef struct {
    VV key;
    IV index;
} Winner;

inline Winner no_winner(void)
{
    Winner w = {(VV)V_HIGHEST, (IV)(-1)};
    return w;
}

/* Row `row` of the displacements, visited s-th: rows go out from vy = 0 (delta, delta - 1, delta + 1,
 * delta - 2, ...), so the winner of a small motion is found early and rarely moves afterwards. The row
 * next to it on the side of vy = 0 (its "inward" row) was visited one or two steps before. */
inline int row_of(int s, int delta)
{
    int k = (s + 1) / 2;
    return s % 2 ? delta - k : delta + k;
}

inline int inward_of(int row, int delta)
{
    return row < delta ? row + 1 : row > delta ? row - 1 : -1;
}

/* Plane p of neigh takes `value` where mask is set and keeps its own elsewhere. */
#define MASKED_STORE(p, value, mask) \
    VSTORE(select(VLOAD(neigh + (p) * plane + i), (value), (mask)), neigh + (p) * plane + i)

/* Visit row `row`, n vote planes at `cur` (its inward row's at `in`, when inward >= 0), and record the
 * keys of the winners' neighbouring displacements for the parabola fit in the planes of `neigh`: left,
 * right (vx -+ 1), up, down (vy -+ 1), NONE outside the range. A winner found in this row gets left,
 * right and its inward neighbour, and waits for the outward one; a winner in the inward row gets this
 * row's key at its column as its outward neighbour. The neighbours are read by a second pass over the
 * row's planes, still in cache, only where some lane needs them: once the winners settle, most rows
 * skip it (recording during the first pass made the whole update twice as slow on PoCL). */
inline void visit_row(Winner *w, __global const V_T *cur, __global const V_T *in, __global float *neigh,
                      size_t i, size_t plane, int n, int delta, int row, int inward, FLV slow, int record)
{
    int vy = row - delta, vyi = inward - delta;
    IV entering = w->index;
    for (int c = 0; c < n; c++) {
        int vx = c - delta;
        VV key = KEY(VLOAD(cur + c * plane + i), vx * vx + vy * vy);
        IV better = key < w->key;
        w->key = select(w->key, key, better);
        w->index = select(w->index, (IV)(row * n + c), better);
    }
    if (!record) return;
    IV here = (w->index >= (IV)(row * n)) & (w->index < (IV)(row * n + n));
    IV there = (w->index >= (IV)(inward * n)) & (w->index < (IV)(inward * n + n)) & (IV)(inward >= 0 ? -1 : 0);
    if (!ANY(here | there)) return;
    IV column = w->index - (IV)(row * n), column_in = entering - (IV)(inward * n);
    FLV left = (FLV)NONE, right = (FLV)NONE, inner = (FLV)NONE, outer = (FLV)NONE;
    for (int c = 0; c < n; c++) {
        int vx = c - delta;
        VV raw = VLOAD(cur + c * plane + i);
        FLV k = FIT(raw, KEY(raw, vx * vx + vy * vy));
        left = select(left, k, column == (IV)(c + 1));
        right = select(right, k, column == (IV)(c - 1));
        outer = select(outer, k, column_in == (IV)c);
        IV at = column == (IV)c;
        if (inward >= 0 && ANY(at)) {
            VV raw_in = VLOAD(in + c * plane + i);
            inner = select(inner, FIT(raw_in, KEY(raw_in, vx * vx + vyi * vyi)), at);
        }
    }
    int inward_slot = inward < row ? 2 : 3, outward_slot = 5 - inward_slot;
    MASKED_STORE(0, left, here);
    MASKED_STORE(1, right, here);
    MASKED_STORE(inward_slot, inner, here);
    MASKED_STORE(outward_slot, select((FLV)NONE, outer, there), here | there);
}

inline void store(Winner *w, __global V_T *best, __global int *index, size_t i)
{
    VSTORE(w->key, best + i);
    VSTORE(w->index, index + i);
}

/* The s-th row visited updates the winners kept in best (keys), index and neigh (s = 0 starts them). */
__kernel void vote_running(__global const V_T *cur, __global const V_T *in, __global const float *moments,
                           __global V_T *best, __global int *index, __global float *neigh, long W, long H,
                           long col0, long count, int delta, int r, float penalty, int record, int s)
{
    long k = get_global_id(0), y = get_global_id(1);
    if (k >= count || y >= H) return;
    long x0 = col0 + k * VEC;
    size_t i = y * W + x0, plane = W * H;
    int n = 2 * delta + 1, row = row_of(s, delta);
    Winner w = no_winner();
    if (s > 0) {
        w.key = VLOAD(best + i);
        w.index = VLOAD(index + i);
    }
    visit_row(&w, cur, in, neigh, i, plane, n, delta, row, inward_of(row, delta),
              slowness(moments, penalty, x0, y, W, H, r), record);
    store(&w, best, index, i);
}

/* The winners from the full table of n * n vote planes, rows in the order vote_running visits them. */
__kernel void winner_table(__global const V_T *table, __global const float *moments, __global V_T *best,
                           __global int *index, __global float *neigh, long W, long H, long col0, long count,
                           int delta, int r, float penalty, int record)
{
    long k = get_global_id(0), y = get_global_id(1);
    if (k >= count || y >= H) return;
    long x0 = col0 + k * VEC;
    size_t i = y * W + x0, plane = W * H;
    int n = 2 * delta + 1;
    FLV slow = slowness(moments, penalty, x0, y, W, H, r);
    Winner w = no_winner();
    for (int s = 0; s < n; s++) {
        int row = row_of(s, delta), inward = inward_of(row, delta);
        visit_row(&w, table + row * n * plane, table + max(inward, 0) * n * plane, neigh, i, plane, n, delta, row,
                  inward, slow, record);
    }
    store(&w, best, index, i);
}

/* Squared differences: planes f0, f0^2, f1, f1^2 (patch means and contrasts after box sums). XOR: planes
 * f0, f1 as 0/1 (edge counts). The sign comparison needs none: its patches hold n values of +-1. */
__kernel void moments(__global const F_T *f0, __global const F_T *f1, __global float *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x, plane = W * H;
#if COMPARE == CMP_SQUARED
    float a = f0[i], b = f1[i];
    out[i] = a;
    out[plane + i] = a * a;
    out[2 * plane + i] = b;
    out[3 * plane + i] = b * b;
#else
    out[i] = f0[i] != 0;
    out[plane + i] = f1[i] != 0;
#endif
}

/* Vertex of the parabola through (-1, a), (0, b), (1, c), b the minimum; 0 where a neighbour is missing
 * or the three are collinear. */
inline float parabola(float a, float b, float c)
{
    float curvature = a - 2.0f * b + c;
    if (!isfinite(a) || !isfinite(c) || !(curvature > 0.0f)) return 0.0f;
    return clamp(0.5f * (a - c) / curvature, -0.5f, 0.5f);
}

/* Relative contrast (sum (f - mean)^2 over sum f^2) below which a patch of frame 0 is flat: no estimate. */
#define FLAT 1e-5f

/* One work-item per pixel; built with VEC = 1 only (its helpers are the scalar builds of the ones above).
 * predicted: frame 1 was warped by the prediction `pred`, which is added back (pyramid levels). An argument,
 * not a define: both cases then share one build with warp and moments. */
#if VEC == 1
__kernel void finish(__global const V_T *best, __global const int *index, __global const float *neigh,
                     __global const float2 *pred, __global const float *moments, __global const F_T *f0,
                     __global float2 *flow, __global float *score, __global uchar *boundary,
                     long W, long H, int delta, int r, float penalty, int subpixel, float threshold,
                     int predicted)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    int n = 2 * delta + 1;
    size_t i = y * W + x, plane = W * H;
    int bi = index[i];
    int2 v = (int2)(bi % n - delta, bi / n - delta);
    long x1 = clamp(x + v.x, 0L, W - 1), y1 = clamp(y + v.y, 0L, H - 1);
    size_t j = y1 * W + x1;
    float count = window_count((int)x, y, W, H, r);
    int norm = v.x * v.x + v.y * v.y;
    /* fitted: the value at the winner of what the parabola is fitted to (see FIT). */
#if COMPARE == CMP_SQUARED
    float fitted = best[i];
    float c0 = contrast(moments[i], moments[plane + i], count);
    float c1 = contrast(moments[2 * plane + j], moments[3 * plane + j], window_count((int)x1, y1, W, H, r));
    float vote = fitted - penalty * c0 * (float)norm;
    bool known = c0 > FLAT * moments[plane + i];
    float s = 1.0f - vote / (c0 + c1);
#else
    float fitted = (float)((best[i] - norm) / (2 * delta * delta + 1)), vote = fitted;
#if COMPARE == CMP_SIGN
    bool known = true;
    float s = 1.0f - 2.0f * vote / count;
#else
    bool known = f0[i] != 0;
    float s = 1.0f - vote / (moments[i] + moments[plane + j]);
#endif
#endif
    float2 w = convert_float2(v);
    if (predicted)
        w += pred[i];
    if (subpixel)
        w += (float2)(parabola(neigh[i], fitted, neigh[plane + i]),
                      parabola(neigh[2 * plane + i], fitted, neigh[3 * plane + i]));
    flow[i] = known ? w : (float2)(NAN);
    score[i] = known ? s : NAN;
    boundary[i] = known && s < threshold;
}
#endif

/* Every other pixel of an image already smoothed against aliasing. */
__kernel void decimate(__global const float *in, __global float *out, long W, long H, long W2, long H2)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W2 || y >= H2) return;
    out[y * W2 + x] = in[min(2 * y, H - 1) * W + min(2 * x, W - 1)];
}

/* A flow field as planes u, v, known (NaN counts as unknown, 0 in u and v), for box sums. */
__kernel void flow_planes(__global const float2 *flow, __global float *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x, plane = W * H;
    float2 f = flow[i];
    bool known = all(isfinite(f));
    out[i] = known ? f.x : 0.0f;
    out[plane + i] = known ? f.y : 0.0f;
    out[2 * plane + i] = known;
}

/* The mean of the known flow over each patch, from the box sums of flow_planes; NaN where none is known. */
__kernel void mean_flow(__global const float *sums, __global float2 *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x, plane = W * H;
    float count = sums[2 * plane + i];
    out[i] = count > 0.0f ? (float2)(sums[i], sums[plane + i]) / count : (float2)(NAN);
}

/* Bilinear interpolation of a W x H field of VALUE_T at (x, y), clamped to the field. */
#define BILINEAR(VALUE_T, field, x, y, W, H, out)                                                          \
    {                                                                                                      \
        float fx = clamp((x), 0.0f, (float)((W) - 1)), fy = clamp((y), 0.0f, (float)((H) - 1));            \
        long xa = (long)fx, ya = (long)fy, xb = min(xa + 1, (long)(W) - 1), yb = min(ya + 1, (long)(H) - 1); \
        float ax = fx - xa, ay = fy - ya;                                                                  \
        VALUE_T top = (1.0f - ax) * field[ya * (W) + xa] + ax * field[ya * (W) + xb];                     \
        VALUE_T bottom = (1.0f - ax) * field[yb * (W) + xa] + ax * field[yb * (W) + xb];                  \
        out = (1.0f - ay) * top + ay * bottom;                                                             \
    }

/* The coarse-to-fine step: the prediction at each fine pixel is `gain` times the coarse flow interpolated
 * bilinearly at its position (coarse pixel X sits at fine pixel X / to_coarse: to_coarse 0.5 and gain 2
 * for the level below, 1 and 1 for a prediction of the image's own size; 0 where it has no estimate),
 * and frame 1's features are warped by it, out(x) = f1(x + pred(x)), bilinearly (binary maps: the
 * nearest pixel), so the finer search is for the residual around a smooth prediction. */
__kernel void warp(__global const F_T *f1, __global const float2 *coarse, __global F_T *out, __global float2 *pred,
                   long W, long H, long Wc, long Hc, float to_coarse, float gain)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float2 f;
    BILINEAR(float2, coarse, to_coarse * x, to_coarse * y, Wc, Hc, f)
    float2 p = all(isfinite(f)) ? gain * f : (float2)(0.0f);
    pred[y * W + x] = p;
#if COMPARE == CMP_XOR
    /* Clamped in float before the conversion: an infinite prediction still reads an edge pixel. */
    long xs = (long)clamp(rint(x + p.x), 0.0f, (float)(W - 1)), ys = (long)clamp(rint(y + p.y), 0.0f, (float)(H - 1));
    out[y * W + x] = f1[ys * W + xs];
#else
    float v;
    BILINEAR(float, f1, x + p.x, y + p.y, W, H, v)
    out[y * W + x] = v;
#endif
}

/* Where a given prediction holds (finite), the search around it replaces the coarse-to-fine one's estimate
 * when it scores better (or the other has none): two windows, the better match kept. */
__kernel void keep_better(__global float2 *flow, __global float *score, __global uchar *boundary,
                          __global const float2 *other_flow, __global const float *other_score,
                          __global const uchar *other_boundary, __global const float2 *prediction, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float mine = score[i], theirs = other_score[i];
    int better = isnan(mine) ? !isnan(theirs) : theirs > mine;
    if (all(isfinite(prediction[i])) && better) {
        flow[i] = other_flow[i];
        score[i] = theirs;
        boundary[i] = other_boundary[i];
    }
}

__kernel void sign_agreement(__global const float *f, __global const float *g, __global int *out, long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    out[i] = (f[i] >= 0) == (g[i] >= 0) ? 1 : -1;
}
