/* color.cl: Hurlbert and Poggio's hue, seed section "Color". Under one source and Lambertian surfaces
 * I^nu = k^nu E(x, y) rho^nu(x, y), so H = I^r / (I^r + I^g) = k^r rho^r / (k^r rho^r + k^g rho^g) does
 * not depend on the effective illumination E and changes only where the albedo does.
 *
 * One work-item per pixel (per CM processor), over a (W, H) grid; ids past the field idle.
 *
 *   hue            H (or the chromaticity pair r / (r+g+b), g / (r+g+b)) and its validity
 *   hue_gradient   H, its validity and its noise-normalised gradient, in one pass over the RGB image
 *   hue_edges      albedo-edge candidates: the normalised gradient above a threshold
 *
 * A pixel is valid when its three channels are finite and the denominator (R + G, or R + G + B for the
 * pair) is at least min_intensity; elsewhere H is NaN, never a quotient of near-zero numbers.
 *
 * Defines: IN_T (uchar|ushort|float), the input's channel type; CHROMA (1: the chromaticity pair,
 * 0: H); FIXED (1: hue_edges compares with a threshold from the host, 0: with the noise estimate
 * computed on the device).
 */
#include "vmcl.h"

#ifndef IN_T
#define IN_T float
#endif
#ifndef CHROMA
#define CHROMA 0
#endif
#ifndef FIXED
#define FIXED 0
#endif

inline float3 rgb_at(__global const IN_T *rgb, size_t i)
{
    return (float3)((float)rgb[3 * i], (float)rgb[3 * i + 1], (float)rgb[3 * i + 2]);
}

/* isfinite on all three channels: a NaN or infinite channel would otherwise pass the sum test or turn
 * the quotient into NaN silently. */
inline int usable(float3 c, float denominator, float min_intensity)
{
    return isfinite(c.x) && isfinite(c.y) && isfinite(c.z) && denominator >= min_intensity;
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

/* H of a valid pixel and its noise gain dH/dI: with independent noise of deviation s on R and G,
 * H = R / (R + G) has deviation s * sqrt(R^2 + G^2) / (R + G)^2. */
inline float2 hue_and_gain(float3 c)
{
    float sum = c.x + c.y;
    return (float2)(c.x / sum, sqrt(c.x * c.x + c.y * c.y) / (sum * sum));
}

/* Forward differences of H towards the right and lower neighbours (the dual-lattice sites the pixel
 * owns, as vmcl.scenes labels them), each divided by its own noise deviation in units of s, so z is
 * Rayleigh-distributed with scale s wherever the albedo is constant, however bright the pixel. z is
 * NaN unless the pixel and both neighbours are valid; the last column and row difference with
 * themselves (0). */
__kernel void hue_gradient(__global const IN_T *rgb, __global float *hue, __global uchar *valid,
                           __global float *z, float min_intensity, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    size_t right = (size_t)y * W + min(x + 1, W - 1), down = (size_t)min(y + 1, H - 1) * W + x;
    float3 c = rgb_at(rgb, i), cr = rgb_at(rgb, right), cd = rgb_at(rgb, down);
    int ok = usable(c, c.x + c.y, min_intensity);
    int all = ok && usable(cr, cr.x + cr.y, min_intensity) && usable(cd, cd.x + cd.y, min_intensity);
    float2 p = hue_and_gain(c), r = hue_and_gain(cr), d = hue_and_gain(cd);
    float zx = (r.x - p.x) / sqrt(p.y * p.y + r.y * r.y);
    float zy = (d.x - p.x) / sqrt(p.y * p.y + d.y * d.y);
    hue[i] = ok ? p.x : NAN;
    valid[i] = ok;
    z[i] = all ? sqrt(zx * zx + zy * zy) : NAN;
}

/* Candidates where z exceeds the threshold: thr[1], the noise rule's high threshold, or the floor if
 * that is larger (FIXED == 0); the floor alone (FIXED == 1). NaN never passes. */
__kernel void hue_edges(__global const float *z, __global const float *thr, __global uchar *edges,
                        float floor_threshold, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
#if FIXED
    float t = floor_threshold;
#else
    float t = fmax(thr[1], floor_threshold);
#endif
    edges[i] = z[i] > t;
}
