/* weighted_median.cl: a field's weighted median over windows whose support stops at brightness edges
 * (vmcl/early/weighted_median.py).
 *
 * One work-item per pixel, every component (COMPS) of it. A pixel to be replaced gathers the voters of its
 * (2R + 1)^2 window into a histogram of bins STEP units wide (private, NBINS long), each weighted by
 * exp(-|I(q) - I(p)| / sigma_colour - |q - p| / sigma_space), I the image's grey level or RGB
 * colour scaled to [0, 1] by `scale` (IN_T: uchar, ushort or float; CHANNELS: 1 or 3): neighbours of
 * another colour, across a brightness edge, hardly count, so a surface's value is not carried over its outline. The median is the
 * first bin where the running weight reaches half the total; the pixel takes the weighted mean of that
 * bin's voters (a value to a fraction of the bin, not its centre). A pixel with no voter in its window
 * keeps its own value.
 */
#include "vmcl.h"

#ifndef NBINS
#define NBINS 64
#endif
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
