/* color.cl: Hurlbert and Poggio's hue, seed section "Color". Under one source and Lambertian surfaces
 * I^nu = k^nu E(x, y) rho^nu(x, y), so H = I^r / (I^r + I^g) = k^r rho^r / (k^r rho^r + k^g rho^g) does
 * not depend on the effective illumination E and changes only where the albedo does.
 *
 * hue: one work-item per pixel (per CM processor), over a (W, H) grid; hue_gradient and hue_edges: one
 * per VEC adjacent pixels (16 on CPUs, whose SIMD lanes then see contiguous loads; 1 on GPUs). Ids past
 * the field idle.
 *
 *   hue            H (or the chromaticity pair r / (r+g+b), g / (r+g+b)) and its validity
 *   hue_gradient   H, its validity and its noise-normalised gradient, in one pass over the RGB image
 *   hue_edges      albedo-edge candidates: the normalised gradient above a threshold
 *
 * A pixel is valid when its three channels are finite and the denominator (R + G, or R + G + B for the
 * pair) is at least min_intensity; elsewhere H is NaN, never a quotient of near-zero numbers.
 *
 * Defines: VEC (1|16); IN_T (uchar|ushort|float), the input's channel type; CHROMA (1: the chromaticity pair,
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
    *ok = isfinite(r) & isfinite(gr) & isfinite(bl) & (sum >= min_intensity);
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
 * its 16 pixels and the 16 below as vectors and computes each pixel's H once, instead of loading every
 * pixel three times one by one (measured 10x slower on PoCL); the pixel right of the chunk and chunks
 * that meet the right border go pixel by pixel. */
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

/* Candidates where z exceeds the threshold: thr[1], the noise rule's high threshold, or the floor if
 * that is larger (FIXED == 0); the floor alone (FIXED == 1). NaN never passes. Work-item i stands for
 * elements [i * VEC, (i + 1) * VEC). */
__kernel void hue_edges(__global const float *z, __global const float *thr, __global uchar *edges,
                        float floor_threshold, long n)
{
    long i0 = get_global_id(0) * VEC;
    if (i0 >= n) return;
#if FIXED
    float t = floor_threshold;
#else
    float t = fmax(thr[1], floor_threshold);
#endif
#if VEC == 16
    if (i0 + 16 <= n) {
        vstore16(convert_uchar16(-(vload16(0, z + i0) > t)), 0, edges + i0);
        return;
    }
#endif
    for (long i = i0; i < min(i0 + VEC, n); i++)
        edges[i] = z[i] > t;
}
