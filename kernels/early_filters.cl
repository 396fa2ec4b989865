/* early_filters.cl, driven by vmcl/early/filters.py.
 * The exact separable Gaussian, the grey conversion, the discrete Laplacian and the
 * difference of Gaussians. Seed section "Edge detection" (Zero-crossings): "The Laplacian of a Gaussian
 * can also be computed by convolution with a Gaussian followed by convolution with a discrete
 * Laplacian"; the Laplacian "is often approximated by the difference of Gaussians". The binomial
 * Gaussian (add and shift on the mesh) is cm_filters.cl's.
 *
 * Work-item (k, y) stands for the VEC processors (pixels) [k * VEC, (k + 1) * VEC) of row y: one vector
 * step where its window lies inside the row, pixel by pixel where it meets a border. VEC = 16 on CPUs,
 * whose SIMD lanes then see contiguous loads (a one-pixel work-item ran the column pass 50 times
 * slower on PoCL), and 1 on GPUs. Borders repeat the edge pixel (clamp), as the binomial passes do, so a
 * constant image stays exactly constant and its Laplacian exactly zero.
 *
 * Defines: VEC (1|16); IN_T (uchar|ushort|float), the input of gauss_rows and to_grey; CHANNELS (1|3)
 * for to_grey; PLANES (1|2) for the Gaussian passes: 2 smooths with two widths in the same loop (the
 * difference of Gaussians), the taps of both packed side by side, the narrower zero-padded to the wider
 * radius.
 */
#define T float
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
#define TO_VT(v) VCAT(convert_, VT)(v)
#define ROW_SEGMENT_REACH 64  /* the widest radius whose border chunks gauss_rows steps as vectors */

/* RGB (or any input type) to float grey, with the host's weights. */
__kernel void to_grey(__global const IN_T *in, __global float *out, float4 weights, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        __global const IN_T *p = in + (y * W + x) * CHANNELS;
#if CHANNELS == 3
        out[y * W + x] = weights.x * (float)p[0] + weights.y * (float)p[1] + weights.z * (float)p[2];
#else
        out[y * W + x] = (float)p[0];
#endif
    }
}

/* Row pass: out[p][y][x] = sum_k taps_p[k] * in[y][x + k - r], every plane from the same loads. */
__kernel void gauss_rows(__global const IN_T *in, __global float *out, __global const float *taps,
                         int r, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    __global const IN_T *row = in + y * W;
    __global float *target = out + y * W;
    int n = 2 * r + 1;
    if (x0 >= r && x0 + VEC + r <= W) {
        VT s0 = (VT)0.0f, s1 = (VT)0.0f;
        for (int k = 0; k < n; k++) {
            VT v = TO_VT(VLOAD(row + x0 + k - r));
            s0 += taps[k] * v;
#if PLANES == 2
            s1 += taps[n + k] * v;
#endif
        }
        VSTORE(s0, target + x0);
#if PLANES == 2
        VSTORE(s1, target + W * H + x0);
#endif
        return;
    }
#if VEC > 1
    /* A chunk whose window meets a border: its row segment, the border pixel repeated past the ends, in
     * private memory, then the same vector steps as the inner chunks (on a small image, such as a coarse
     * pyramid level, most chunks meet a border). Radii past ROW_SEGMENT_REACH go pixel by pixel below. */
    if (r <= ROW_SEGMENT_REACH) {
        float segment[VEC + 2 * ROW_SEGMENT_REACH];
        for (int j = 0; j < VEC + 2 * r; j++) segment[j] = (float)row[clamp(x0 + j - r, 0L, W - 1)];
        VT s0 = (VT)0.0f, s1 = (VT)0.0f;
        for (int k = 0; k < n; k++) {
            VT v = VLOAD(segment + k);
            s0 += taps[k] * v;
#if PLANES == 2
            s1 += taps[n + k] * v;
#endif
        }
        float t0[VEC], t1[VEC];
        VSTORE(s0, t0);
        VSTORE(s1, t1);
        for (long x = x0; x < min(x0 + VEC, W); x++) {
            target[x] = t0[x - x0];
#if PLANES == 2
            target[W * H + x] = t1[x - x0];
#endif
        }
        return;
    }
#endif
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float s0 = 0.0f, s1 = 0.0f;
        for (int k = 0; k < n; k++) {
            float v = (float)row[clamp(x + k - r, 0L, W - 1)];
            s0 += taps[k] * v;
#if PLANES == 2
            s1 += taps[n + k] * v;
#endif
        }
        target[x] = s0;
#if PLANES == 2
        target[W * H + x] = s1;
#endif
    }
}

/* Column pass; PLANES == 2 writes the first plane minus the second (the host orders the widths for the
 * sign it wants). Rows are clamped per work-item, so only a row's ragged end goes pixel by pixel. */
__kernel void gauss_cols(__global const float *in, __global float *out, __global const float *taps,
                         int r, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    int n = 2 * r + 1;
    if (x0 + VEC <= W) {
        VT s0 = (VT)0.0f, s1 = (VT)0.0f;
        for (int k = 0; k < n; k++) {
            long yy = clamp(y + k - r, 0L, H - 1);
            s0 += taps[k] * VLOAD(in + yy * W + x0);
#if PLANES == 2
            s1 += taps[n + k] * VLOAD(in + W * H + yy * W + x0);
#endif
        }
#if PLANES == 2
        s0 -= s1;
#endif
        VSTORE(s0, out + y * W + x0);
        return;
    }
    for (long x = x0; x < W; x++) {
        float s0 = 0.0f, s1 = 0.0f;
        for (int k = 0; k < n; k++) {
            long yy = clamp(y + k - r, 0L, H - 1);
            s0 += taps[k] * in[yy * W + x];
#if PLANES == 2
            s1 += taps[n + k] * in[W * H + yy * W + x];
#endif
        }
#if PLANES == 2
        s0 -= s1;
#endif
        out[y * W + x] = s0;
    }
}

/* The 5-point Laplacian. Each term is a difference with the centre, so a locally constant field gives
 * exactly 0 (summing the four neighbours first would round). */
#define LAPLACIAN(c, l, r, u, d) (((l) - (c)) + ((r) - (c))) + (((u) - (c)) + ((d) - (c)))

__kernel void laplacian(__global const float *in, __global float *out, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    __global const float *mid = in + y * W;
    __global const float *up = in + max(y - 1, 0L) * W;
    __global const float *down = in + min(y + 1, H - 1) * W;
    if (x0 >= 1 && x0 + VEC + 1 <= W) {
        VT c = VLOAD(mid + x0);
        VSTORE(LAPLACIAN(c, VLOAD(mid + x0 - 1), VLOAD(mid + x0 + 1), VLOAD(up + x0), VLOAD(down + x0)),
               out + y * W + x0);
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        float c = mid[x];
        out[y * W + x] = LAPLACIAN(c, mid[max(x - 1, 0L)], mid[min(x + 1, W - 1)], up[x], down[x]);
    }
}
