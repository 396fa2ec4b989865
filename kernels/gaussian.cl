/* gaussian.cl: the exact separable Gaussian, the grey conversion, the discrete Laplacian and the
 * difference of Gaussians. Seed section "Edge detection" (Zero-crossings): "The Laplacian of a Gaussian
 * can also be computed by convolution with a Gaussian followed by convolution with a discrete
 * Laplacian"; the Laplacian "is often approximated by the difference of Gaussians". The binomial
 * Gaussian (add and shift on the mesh) is filters.cl's.
 *
 * One work-item per pixel. Borders repeat the edge pixel (clamp), as the binomial passes do, so a
 * constant image stays exactly constant and its Laplacian exactly zero.
 *
 * Defines: IN_T (uchar|ushort|float) and CHANNELS (1|3) for the kernels that read the input image;
 * PLANES (1|2) for the Gaussian passes: 2 smooths with two widths in the same loop (the difference of
 * Gaussians), the taps of both packed side by side, the narrower zero-padded to the wider radius.
 */
#include "vmcl.h"

#ifndef IN_T
#define IN_T float
#endif
#ifndef CHANNELS
#define CHANNELS 1
#endif
#ifndef PLANES
#define PLANES 1
#endif

/* The grey value of pixel x of an input row: RGB becomes a weighted sum (weights from the host). */
#if CHANNELS == 3
#define GREY(row, at, w) ((w).x * (float)(row)[3 * (at)] + (w).y * (float)(row)[3 * (at) + 1] \
                          + (w).z * (float)(row)[3 * (at) + 2])
#else
#define GREY(row, at, w) ((float)(row)[at])
#endif

__kernel void to_grey(__global const IN_T *in, __global float *out, float4 weights, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    __global const IN_T *row = in + y * W * CHANNELS;
    out[y * W + x] = GREY(row, x, weights);
}

/* Row pass, fused with the grey conversion so the input is read once: out[p][y][x] = sum_k w_p[k] *
 * grey(x + k - r, y), every plane from the same loads. */
__kernel void gauss_rows(__global const IN_T *in, __global float *out, __global const float *taps,
                         int r, float4 weights, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    __global const IN_T *row = in + y * W * CHANNELS;
    int n = 2 * r + 1;
    float s0 = 0.0f, s1 = 0.0f;
    for (int k = 0; k < n; k++) {
        long xx = clamp(x + k - r, 0L, W - 1);
        float v = GREY(row, xx, weights);
        s0 += taps[k] * v;
#if PLANES == 2
        s1 += taps[n + k] * v;
#endif
    }
    out[y * W + x] = s0;
#if PLANES == 2
    out[W * H + y * W + x] = s1;
#endif
}

/* Column pass: neighbouring work-items read neighbouring addresses of each row, so the strided walk of
 * one work-item is still a contiguous sweep for the work-group. PLANES == 2 writes the first plane
 * minus the second: the host orders the widths for the sign it wants. */
__kernel void gauss_cols(__global const float *in, __global float *out, __global const float *taps,
                         int r, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    int n = 2 * r + 1;
    float s0 = 0.0f, s1 = 0.0f;
    for (int k = 0; k < n; k++) {
        long yy = clamp(y + k - r, 0L, H - 1);
        s0 += taps[k] * in[yy * W + x];
#if PLANES == 2
        s1 += taps[n + k] * in[W * H + yy * W + x];
#endif
    }
#if PLANES == 2
    out[y * W + x] = s0 - s1;
#else
    out[y * W + x] = s0;
#endif
}

/* The 5-point Laplacian. Each term is a difference with the centre, so a locally constant field gives
 * exactly 0 (summing the four neighbours first would round). */
__kernel void laplacian(__global const float *in, __global float *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float c = in[i];
    float l = in[y * W + max(x - 1, 0L)], r = in[y * W + min(x + 1, W - 1)];
    float u = in[max(y - 1, 0L) * W + x], d = in[min(y + 1, H - 1) * W + x];
    out[i] = ((l - c) + (r - c)) + ((u - c) + (d - c));
}
