/* color.cl: Hurlbert and Poggio's hue, seed section "Color". Under one source and Lambertian surfaces
 * I^nu = k^nu E(x, y) rho^nu(x, y), so H = I^r / (I^r + I^g) = k^r rho^r / (k^r rho^r + k^g rho^g) does
 * not depend on the effective illumination E and changes only where the albedo does.
 *
 * hue: one work-item per pixel (per CM processor), over a (W, H) grid; hue_gradient and hue_edges: one
 * per VEC adjacent pixels (16 on CPUs, whose SIMD lanes then see contiguous loads; 1 on GPUs);
 * hue_histogram: one per band of rows; hue_threshold: one. Ids past the field idle.
 *
 *   hue            H (or the chromaticity pair r / (r+g+b), g / (r+g+b)) and its validity
 *   hue_gradient   H, its validity and its noise-normalised gradient, in one pass over the RGB image
 *   hue_histogram  histograms of the normalised gradient over 1/16-octave bins, one per band of rows
 *   hue_threshold  the noise rule's threshold from the median of those histograms
 *   hue_edges      albedo-edge candidates: the normalised gradient above a threshold
 *
 * A pixel is valid when its three channels are finite and the denominator (R + G, or R + G + B for the
 * pair) is at least min_intensity; elsewhere H is NaN, never a quotient of near-zero numbers.
 *
 * Defines: VEC (1|16); IN_T (uchar|ushort|float), the input's channel type; CHROMA (1: the chromaticity pair,
 * 0: H).
 */
#include "vmcl.h"

#ifndef IN_T
#define IN_T float
#endif
#ifndef CHROMA
#define CHROMA 0
#endif

inline float3 rgb_at(__global const IN_T *rgb, size_t i)
{
    return (float3)((float)rgb[3 * i], (float)rgb[3 * i + 1], (float)rgb[3 * i + 2]);
}

/* isfinite on all three channels: a NaN or infinite channel would otherwise pass the sum test or turn
 * the quotient into NaN silently; and on the sum, which overflows float32 for channels near its largest
 * (R / inf gave a hue of 0, marked valid). */
inline int usable(float3 c, float denominator, float min_intensity)
{
    return isfinite(c.x) && isfinite(c.y) && isfinite(c.z) && isfinite(denominator) && denominator >= min_intensity;
}

__kernel void hue(__global const IN_T *rgb, __global float *out, __global uchar *valid, float min_intensity,
                  long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    float3 c = rgb_at(rgb, i);
#if CHROMA
    float sum = c.x + c.y + c.z;
    int ok = usable(c, sum, min_intensity);
    out[2 * i] = ok ? c.x / sum : NAN;
    out[2 * i + 1] = ok ? c.y / sum : NAN;
#else
    float sum = c.x + c.y;
    int ok = usable(c, sum, min_intensity);
    out[i] = ok ? c.x / sum : NAN;
#endif
    valid[i] = ok;
}

/* H of a pixel and its noise gain dH/dI: with independent noise of deviation s on R and G,
 * H = R / (R + G) has deviation s * sqrt(R^2 + G^2) / (R + G)^2. H is NaN where the pixel is not
 * valid, so every difference taken with it is NaN too: that is how z learns its neighbours' validity
 * without loading their flags. */
inline float2 hue_and_gain(__global const IN_T *rgb, size_t i, float min_intensity)
{
    float3 c = rgb_at(rgb, i);
    float sum = c.x + c.y;
    return (float2)(usable(c, sum, min_intensity) ? c.x / sum : NAN,
                    sqrt(c.x * c.x + c.y * c.y) / (sum * sum));
}

/* The forward difference of H divided by its noise deviation in units of s (NaN if either is). */
#define NORMALISED(h, g, hn, gn) (((hn) - (h)) / sqrt((g) * (g) + (gn) * (gn)))

#if VEC == 16
#define IN16 VCAT(IN_T, 16)
/* The same for 16 adjacent pixels from p: three contiguous vector loads of interleaved RGB, split into
 * planes by swizzles (R at 0, 3, ..., 45; G one on; B two on). ok is -1 where valid, as comparisons give. */
inline void hue_and_gain16(__global const IN_T *p, float min_intensity, float16 *h, float16 *g, int16 *ok)
{
    float16 a = convert_float16(vload16(0, p)), b = convert_float16(vload16(1, p)),
            c = convert_float16(vload16(2, p));
    float16 r = (float16)(a.s0369, a.scf, b.s258b, b.se, c.s147a, c.sd);
    float16 gr = (float16)(a.s147a, a.sd, b.s0369, b.scf, c.s258b, c.se);
    float16 bl = (float16)(a.s258b, a.se, b.s147a, b.sd, c.s0369, c.scf);
    float16 sum = r + gr;
    *ok = isfinite(r) & isfinite(gr) & isfinite(bl) & isfinite(sum) & (sum >= min_intensity);
    *h = select((float16)NAN, r / sum, *ok);
    *g = sqrt(r * r + gr * gr) / (sum * sum);
}
#endif

/* Forward differences of H towards the right and lower neighbours (the dual-lattice sites the pixel
 * owns, as vmcl.scenes labels them), each divided by its own noise deviation in units of s, so z is
 * Rayleigh-distributed with scale s wherever the albedo is constant, however bright the pixel. z is
 * NaN unless the pixel and both neighbours are valid; the last column and row difference with
 * themselves (0).
 *
 * Work-item (k, y) stands for pixels [k * VEC, (k + 1) * VEC) of row y. With VEC = 16 (CPUs) it loads
 * its 16 pixels and the 16 below with contiguous vector loads and splits the channels by swizzles (each
 * row's H is computed twice, for its own row and for the row above), where one work-item per pixel
 * loaded three pixels channel by channel: that took 37 ms at 1024^2 on PoCL, this 3 to 5 ms. The pixel
 * right of the chunk, and chunks that meet the right border, go pixel by pixel. */
__kernel void hue_gradient(__global const IN_T *rgb, __global float *hue, __global uchar *valid,
                           __global float *z, float min_intensity, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    size_t row = (size_t)y * W, below = (size_t)min(y + 1, H - 1) * W;
#if VEC == 16
    if (x0 + 16 < W) {
        float16 h, g, hd, gd;
        int16 ok, ok_below;
        hue_and_gain16(rgb + 3 * (row + x0), min_intensity, &h, &g, &ok);
        hue_and_gain16(rgb + 3 * (below + x0), min_intensity, &hd, &gd, &ok_below);
        float2 next = hue_and_gain(rgb, row + x0 + 16, min_intensity);
        float16 hr = (float16)(h.s1234, h.s5678, h.s9abc, h.sdef, next.x);
        float16 gr = (float16)(g.s1234, g.s5678, g.s9abc, g.sdef, next.y);
        float16 zx = NORMALISED(h, g, hr, gr), zy = NORMALISED(h, g, hd, gd);
        vstore16(h, 0, hue + row + x0);
        vstore16(convert_uchar16(-ok), 0, valid + row + x0);
        vstore16(sqrt(zx * zx + zy * zy), 0, z + row + x0);
        return;
    }
#endif
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float2 p = hue_and_gain(rgb, row + x, min_intensity),
               r = hue_and_gain(rgb, row + min(x + 1, W - 1), min_intensity),
               d = hue_and_gain(rgb, below + x, min_intensity);
        float zx = NORMALISED(p.x, p.y, r.x, r.y), zy = NORMALISED(p.x, p.y, d.x, d.y);
        hue[row + x] = p.x;
        valid[row + x] = !isnan(p.x);
        z[row + x] = sqrt(zx * zx + zy * zy);
    }
}

/* The noise estimate needs the median of z over the valid pixels, whose range is unknown until z is
 * computed. Rather than read z's maximum back to the host for the range of linear bins, the histogram
 * bins z by its float bit pattern: the exponent and the KEY_BITS leading mantissa bits, bins 1/16 of an
 * octave wide from the smallest float to infinity. That is a relative resolution of 6% at every scale,
 * where linear bins over [0, max] can be wider than the median itself when a few strong edges set the
 * maximum. Work-item b counts rows [b * rows, (b + 1) * rows) serially (contiguous reads) into its own
 * histogram, so counts are exact and need no atomics. NaN (pixels without a valid neighbourhood) is not
 * counted; z >= 0, so the sign bit is 0. */
#define KEY_BITS 4
#define KEY_SHIFT (23 - KEY_BITS)
#define KEY_BINS ((0x7F800000u >> KEY_SHIFT) + 1) /* the last bin holds infinity */

__kernel void hue_histogram(__global const float *z, __global int *counts, long rows, long W, long H)
{
    long b = get_global_id(0), y0 = b * rows;
    if (y0 >= H) return;
    __global int *h = counts + b * KEY_BINS;
    for (uint k = 0; k < KEY_BINS; k++) h[k] = 0;
    for (long i = y0 * W, end = min(y0 + rows, H) * W; i < end; i++) {
        float v = z[i];
        if (!isnan(v)) h[as_uint(fabs(v)) >> KEY_SHIFT]++;  /* fabs: -0.0's sign bit is past the bins */
    }
}

/* threshold[0] = max(factor * median, floor_threshold), the median being np.median's order statistic
 * (N - 1) / 2 with the values of a bin spread evenly across it (bin k covers [as_float(k << KEY_SHIFT),
 * as_float((k + 1) << KEY_SHIFT))). With no valid pixel, the floor. One work-group of THRESHOLD_ITEMS:
 * its work-items total the bands' histograms bin by bin into local memory, then one of them walks the
 * bins in local memory. (A single work-item summing every band's every bin read them one after another:
 * 25 ms on an H200, with a band per row, half of its whole frame; the walk reads 4081 local bins.) */
#define THRESHOLD_ITEMS 256

__kernel __attribute__((reqd_work_group_size(THRESHOLD_ITEMS, 1, 1)))
void hue_threshold(__global const int *counts, __global float *threshold, long bands, float factor,
                   float floor_threshold)
{
    __local long merged[KEY_BINS];  /* 32,648 bytes: within OpenCL's least local memory, 32 KiB */
    for (uint k = get_local_id(0); k < KEY_BINS; k += THRESHOLD_ITEMS) {
        long c = 0;
        for (long b = 0; b < bands; b++) c += counts[b * KEY_BINS + k];
        merged[k] = c;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (get_local_id(0) != 0) return;
    long total = 0;
    for (uint k = 0; k < KEY_BINS; k++) total += merged[k];
    float median = 0.0f, p = 0.5f * (float)(total - 1);
    long below = 0;
    for (uint k = 0; k < KEY_BINS && total > 0; k++) {
        long c = merged[k];
        if (c > 0 && (float)(below + c) > p) {
            float lo = as_float(k << KEY_SHIFT), hi = as_float((k + 1) << KEY_SHIFT);
            median = lo + (p - (float)below + 0.5f) / (float)c * (hi - lo);
            break;
        }
        below += c;
    }
    threshold[0] = fmax(factor * median, floor_threshold);
}

/* Candidates where z exceeds the threshold: threshold[0] from hue_threshold, or with `fixed` the host's
 * fixed_threshold (threshold is then not read; an argument, not a define: one build on a first run).
 * NaN never passes. Work-item i stands for elements [i * VEC,
 * (i + 1) * VEC). */
__kernel void hue_edges(__global const float *z, __global const float *threshold, __global uchar *edges,
                        float fixed_threshold, long n, int fixed)
{
    long i0 = get_global_id(0) * VEC;
    if (i0 >= n) return;
    float t = fixed ? fixed_threshold : threshold[0];
#if VEC == 16
    if (i0 + 16 <= n) {
        vstore16(convert_uchar16(-(vload16(0, z + i0) > t)), 0, edges + i0);
        return;
    }
#endif
    for (long i = i0; i < min(i0 + VEC, n); i++)
        edges[i] = z[i] > t;
}
