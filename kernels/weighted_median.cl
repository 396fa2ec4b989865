/* weighted_median.cl: a field's weighted median over windows whose support stops at brightness edges
 * (vmcl/early/weighted_median.py).
 *
 * A pixel to be replaced weighs each voter q of its window (the rows and columns at multiples of `stride`
 * from its own, within `radius`) by exp(-|I(q) - I(p)| / sigma_colour - |q - p| / sigma_space), I the
 * image's grey level or RGB colour scaled to [0, 1] by `scale`: neighbours of another colour, across a
 * brightness edge, hardly count, so a surface's value is not carried over its outline. The values fall
 * into bins STEP units wide; the median is the first bin where the running weight reaches half the total,
 * and the pixel takes the weighted mean of that bin's voters (a value to a fraction of the bin, not its
 * centre). A pixel with no voter in its window keeps its own value. Two kernels compute it:
 *
 *   weighted_median         one work-item per pixel, every component (COMPS) of it: the voters gathered
 *                           into a private histogram (NBINS long) as they are visited, so any window
 *                           fits; its scattered bins keep it to one pixel at a time.
 *   weighted_median_bisect  VEC adjacent pixels per work-item, for windows of at most MAX_VOTERS voters:
 *                           the voters' weights and bins are kept, and the median's bin is found by
 *                           bisection (the first bin whose weight at or below it reaches half the total,
 *                           `rounds` halvings), so every step is a vector step over the VEC pixels
 *                           (a CPU's SIMD lanes take them together). The image comes as float planes.
 *
 * Both give the median's bin by the same rule; the histogram adds a bin's weights and then the bins in
 * order, the bisection the weights at or below a bin voter by voter, so a total within rounding of half
 * can fall on the next bin in one and not the other, and the weights' exp may differ in its last bit
 * between the scalar and the vector forms. A program holds one of them, the one its defines name (NBINS
 * or MAX_VOTERS), so a first run compiles only what it uses.
 */
#include "vmcl.h"

#ifndef CHANNELS
#define CHANNELS 1
#endif
#ifndef IN_T
#define IN_T float
#endif

/* The field's components, interleaved per pixel (1, or 2 for a flow): each takes its own median, and the
 * voters' weights, the costly part, are found once for all. */
#ifndef COMPS
#define COMPS 1
#endif

#ifdef NBINS  /* each program holds the one kernel the host asks for: its defines say which */
__kernel void weighted_median(__global const float *values, __global const uchar *voters,
                              __global const uchar *where, __global const IN_T *image, __global float *out,
                              long W, long H, int radius, float inv_colour, __global const float *spatial,
                              float scale, float low, float step, int bins, int stride)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x;
    __global const float *own = values + i * COMPS;
    __global float *mine = out + i * COMPS;
    if (!where[i]) {
        for (int k = 0; k < COMPS; k++) mine[k] = own[k];
        return;
    }
    float weight[COMPS][NBINS], sum[COMPS][NBINS], total[COMPS];
    for (int k = 0; k < COMPS; k++) {
        total[k] = 0.0f;
        for (int b = 0; b < bins; b++) { weight[k][b] = 0.0f; sum[k][b] = 0.0f; }
    }
    float centre[CHANNELS];
    for (int c = 0; c < CHANNELS; c++) centre[c] = scale * (float)image[i * CHANNELS + c];
    int side = 2 * radius + 1;
    /* The window's rows and columns at multiples of `stride` from the centre's. */
    long top = y - (min(y, (long)radius) / stride) * stride, left = x - (min(x, (long)radius) / stride) * stride;
    for (long yy = top; yy <= min(y + radius, H - 1); yy += stride) {
        __global const float *row = spatial + (yy - y + radius) * side + radius - x;
        for (long xx = left; xx <= min(x + radius, W - 1); xx += stride) {
            size_t j = yy * W + xx;
            if (!voters[j]) continue;
            __global const float *v = values + j * COMPS;
            int any = 0;
            for (int k = 0; k < COMPS; k++) any |= !isnan(v[k]);
            if (!any) continue;
            float colour = 0.0f;
            for (int c = 0; c < CHANNELS; c++) {
                float d = scale * (float)image[j * CHANNELS + c] - centre[c];
                colour += d * d;
            }
            float w = row[xx] * exp(-sqrt(colour) * inv_colour);
            for (int k = 0; k < COMPS; k++) {
                if (isnan(v[k])) continue;  /* a NaN never votes */
                int b = clamp((int)floor((v[k] - low) / step), 0, bins - 1);
                weight[k][b] += w;
                sum[k][b] += w * v[k];
                total[k] += w;
            }
        }
    }
    for (int k = 0; k < COMPS; k++) {
        if (!(total[k] > 0.0f)) { mine[k] = own[k]; continue; }
        float running = 0.0f;
        int b = 0;
        for (; b < bins - 1; b++) {
            running += weight[k][b];
            if (running >= 0.5f * total[k]) break;
        }
        /* The bin reached holds weight (b < bins - 1 breaks on a positive step; the last bin holds the rest). */
        mine[k] = weight[k][b] > 0.0f ? sum[k][b] / weight[k][b] : own[k];
    }
}

#endif

/* ------------------------------------------------------------------ VEC pixels per work-item */
#ifdef MAX_VOTERS

#if VEC == 1
#define LANE_IDS 0
#define TO_VIT(x) convert_int(x)
#define ANY(c) (c)
#else
#define LANE_IDS ((VIT)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
#define TO_VIT(x) VCAT(convert_int, VEC)(x)
#define ANY(c) any(c)
#endif

/* Component k of the pixels row[a .. a + VEC) of a field of COMPS interleaved components, the nearest
 * pixel's value past the row's ends (such voters weigh nothing): vmcl.h's clamped_chunk for one component. */
inline VFLOAT component_chunk(__global const float *row, long a, long W, int k)
{
#if COMPS == 1
    return clamped_chunk(row, a, W);
#elif VEC == 1
    return row[clamp(a, 0L, W - 1) * COMPS + k];
#else
    if (a >= 0 && a + VEC <= W) {
        float16 p = vload16(0, row + 2 * a), q = vload16(0, row + 2 * a + 16);
        return k == 0 ? (float16)(p.even, q.even) : (float16)(p.odd, q.odd);
    }
    float t[VEC];
    for (int i = 0; i < VEC; i++) t[i] = row[clamp(a + i, 0L, W - 1) * COMPS + k];
    return vload16(0, t);
#endif
}

/* The flags row[a .. a + VEC) as floats, the nearest pixel's past the row's ends. */
inline VFLOAT flags_chunk(__global const uchar *row, long a, long W)
{
#if VEC == 1
    return (float)row[clamp(a, 0L, W - 1)];
#else
    if (a >= 0 && a + VEC <= W) return convert_float16(vload16(0, row + a));
    float t[VEC];
    for (int i = 0; i < VEC; i++) t[i] = (float)row[clamp(a + i, 0L, W - 1)];
    return vload16(0, t);
#endif
}

/* planes: the image's CHANNELS planes (C x H x W floats in levels of its own type, `scale` to [0, 1]);
 * reach: the window's steps of `stride` each way, (2 reach + 1)^2 <= MAX_VOTERS; rounds: the bisection's
 * halvings, ceil(log2(bins)). The rest as weighted_median's. */
__kernel void weighted_median_bisect(__global const float *values, __global const uchar *voters,
                                     __global const uchar *where, __global const float *planes,
                                     __global float *out, long W, long H, int radius, float inv_colour,
                                     __global const float *spatial, float scale, float low, float step,
                                     int bins, int stride, int reach, int rounds)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    long end = min(x0 + VEC, W);
    VFLOAT chosen = flags_chunk(where + y * W, x0, W);
    if (!ANY(chosen != 0.0f)) {
        for (long x = x0; x < end; x++)
            for (int k = 0; k < COMPS; k++) out[(y * W + x) * COMPS + k] = values[(y * W + x) * COMPS + k];
        return;
    }
    VFLOAT centre[CHANNELS];
    for (int c = 0; c < CHANNELS; c++) centre[c] = scale * clamped_chunk(planes + (c * H + y) * W, x0, W);
    VIT xs = (VIT)(int)x0 + LANE_IDS;
    int side = 2 * radius + 1, across = 2 * reach + 1;
    /* Each position's weight and its bin per component: `bins`, which no sum counts, where it does not vote
     * (outside the image, not a voter, or its value NaN), as the one-pixel kernel skips it. */
    VFLOAT weight[MAX_VOTERS], value[COMPS][MAX_VOTERS];
    VIT bin[COMPS][MAX_VOTERS];
    int n = 0;
    for (int sy = -reach; sy <= reach; sy++) {
        long yy = y + sy * stride, row = clamp(yy, 0L, H - 1);
        for (int sx = -reach; sx <= reach; sx++, n++) {
            int dx = sx * stride;
            VFLOAT colour = 0.0f;
            for (int c = 0; c < CHANNELS; c++) {
                VFLOAT d = scale * clamped_chunk(planes + (c * H + row) * W, x0 + dx, W) - centre[c];
                colour += d * d;
            }
            VFLOAT w = spatial[(sy * stride + radius) * side + dx + radius] * exp(-sqrt(colour) * inv_colour);
            VIT votes = (xs + dx >= 0) & (xs + dx < (int)W) & (flags_chunk(voters + row * W, x0 + dx, W) != 0.0f);
            if (yy < 0 || yy >= H) votes = (VIT)0;
            weight[n] = select((VFLOAT)0.0f, w, votes);
            for (int k = 0; k < COMPS; k++) {
                VFLOAT v = component_chunk(values + row * W * COMPS, x0 + dx, W, k);
                value[k][n] = v;
                bin[k][n] = select(clamp(TO_VIT(floor((v - low) / step)), 0, bins - 1), (VIT)bins,
                                   isnan(v) | (votes == 0));
            }
        }
    }
    int count = across * across;
    for (int k = 0; k < COMPS; k++) {
        VFLOAT total = 0.0f;
        for (int m = 0; m < count; m++) total += select((VFLOAT)0.0f, weight[m], bin[k][m] < bins);
        /* The first bin b whose weight at or below it reaches half the total: in [lo, hi] throughout. */
        VIT lo = 0, hi = bins - 1;
        for (int r = 0; r < rounds; r++) {
            VIT middle = (lo + hi) >> 1;
            VFLOAT below = 0.0f;
            for (int m = 0; m < count; m++) below += select((VFLOAT)0.0f, weight[m], bin[k][m] <= middle);
            VIT enough = below >= 0.5f * total;
            hi = select(hi, middle, enough);
            lo = select(middle + 1, lo, enough);
        }
        VFLOAT in_bin = 0.0f, sum = 0.0f;
        for (int m = 0; m < count; m++) {
            VIT there = bin[k][m] == lo;
            in_bin += select((VFLOAT)0.0f, weight[m], there);
            sum += select((VFLOAT)0.0f, weight[m] * value[k][m], there);
        }
        VFLOAT own = component_chunk(values + y * W * COMPS, x0, W, k);
        VFLOAT found = select(own, sum / in_bin, (chosen != 0.0f) & (total > 0.0f) & (in_bin > 0.0f));
#if VEC == 1
        out[(y * W + x0) * COMPS + k] = found;
#else
        float t[VEC];
        vstore16(found, 0, t);
        for (long x = x0; x < end; x++) out[(y * W + x) * COMPS + k] = t[x - x0];
#endif
    }
}
#endif
