/* weighted_median.cl: a field's weighted median over windows whose support stops at brightness edges
 * (vmcl/early/weighted_median.py).
 *
 * One work-item per pixel. A pixel to be replaced gathers the voters of its (2R + 1)^2 window into a
 * histogram of bins STEP units wide (private, NBINS long), each weighted by
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

__kernel void weighted_median(__global const float *values, __global const uchar *voters,
                              __global const uchar *where, __global const IN_T *image, __global float *out,
                              long W, long H, int radius, float inv_colour, __global const float *spatial,
                              float scale, float low, float step, int bins, int stride)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x;
    float own = values[i];
    if (!where[i]) { out[i] = own; return; }
    float weight[NBINS], sum[NBINS];
    for (int b = 0; b < bins; b++) { weight[b] = 0.0f; sum[b] = 0.0f; }
    float centre[CHANNELS];
    for (int c = 0; c < CHANNELS; c++) centre[c] = scale * (float)image[i * CHANNELS + c];
    float total = 0.0f;
    int side = 2 * radius + 1;
    /* The window's rows and columns at multiples of `stride` from the centre's. */
    long top = y - (min(y, (long)radius) / stride) * stride, first = x - (min(x, (long)radius) / stride) * stride;
    for (long yy = top; yy <= min(y + radius, H - 1); yy += stride) {
        __global const float *row = spatial + (yy - y + radius) * side + radius - x;
        for (long xx = first; xx <= min(x + radius, W - 1); xx += stride) {
            size_t j = yy * W + xx;
            float v = values[j];
            if (!voters[j] || isnan(v)) continue;
            float colour = 0.0f;
            for (int c = 0; c < CHANNELS; c++) {
                float d = scale * (float)image[j * CHANNELS + c] - centre[c];
                colour += d * d;
            }
            float w = row[xx] * exp(-sqrt(colour) * inv_colour);
            int b = clamp((int)floor((v - low) / step), 0, bins - 1);
            weight[b] += w;
            sum[b] += w * v;
            total += w;
        }
    }
    if (!(total > 0.0f)) { out[i] = own; return; }
    float running = 0.0f;
    int b = 0;
    for (; b < bins - 1; b++) {
        running += weight[b];
        if (running >= 0.5f * total) break;
    }
    /* The bin reached holds weight (b < bins - 1 breaks on a positive step; the last bin holds the rest). */
    out[i] = weight[b] > 0.0f ? sum[b] / weight[b] : own;
}
