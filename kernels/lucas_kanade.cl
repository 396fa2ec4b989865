/* lucas_kanade.cl: Lucas-Kanade steps that refine a dense flow (vmcl/early/lucas_kanade.py).
 *
 *   lk_terms  at each pixel, brightness constancy linearised about its current flow u: frame 1 read at
 *             x + u (bilinearly), the spatial gradient (central differences, frame 0's at x and frame 1's
 *             at x + u averaged: the symmetric form, whose error is second order in the remaining step)
 *             and the temporal difference f1(x + u) - f0(x); written as the five products the normal
 *             equations need, one plane each (xx, xy, yy, xt, yt: gx gx, gx gy, gy gy, gx gt, gy gt), the
 *             brightness in the units that gain carries it to
 *   lk_step   each pixel's 2 x 2 normal equations from those products summed over its window (the caller
 *             smooths each plane with the window's Gaussian), regularised by ridge on the diagonal so
 *             that flat or one-directional windows move little, solved, and the step added to the flow,
 *             each component held within +-limit px (the linearisation holds only near the current flow)
 *
 * Layout: frames and planes row-major W x H float (the frames grey, smoothed by the caller); the flow
 * H x W x 2 interleaved (u, v). One work-item per pixel. A pixel whose flow is not finite, or whose flow
 * carries it out of frame 1, gives no products and keeps its flow.
 */
#include "vmcl.h"
#include "sampling.h"

__kernel void lk_terms(__global const float *f0, __global const float *f1, __global const float *flow,
                       float gain, __global float *xx, __global float *xy, __global float *yy,
                       __global float *xt, __global float *yt, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float u = flow[2 * i], v = flow[2 * i + 1];
    float sx = (float)x + u, sy = (float)y + v;
    float gx = 0.0f, gy = 0.0f, gt = 0.0f;
    if (isfinite(u) && isfinite(v) && sx >= 0.0f && sy >= 0.0f && sx <= (float)(W - 1) && sy <= (float)(H - 1)) {
        long xl = max(x - 1, 0L), xr = min(x + 1, W - 1), yu = max(y - 1, 0L), yd = min(y + 1, H - 1);
        float g0x = 0.5f * (f0[y * W + xr] - f0[y * W + xl]);
        float g0y = 0.5f * (f0[yd * W + x] - f0[yu * W + x]);
        float g1x = 0.5f * (bilinear_clamped(f1, sx + 1.0f, sy, W, H) - bilinear_clamped(f1, sx - 1.0f, sy, W, H));
        float g1y = 0.5f * (bilinear_clamped(f1, sx, sy + 1.0f, W, H) - bilinear_clamped(f1, sx, sy - 1.0f, W, H));
        gx = 0.5f * gain * (g0x + g1x);
        gy = 0.5f * gain * (g0y + g1y);
        gt = gain * (bilinear_clamped(f1, sx, sy, W, H) - f0[i]);
    }
    xx[i] = gx * gx;
    xy[i] = gx * gy;
    yy[i] = gy * gy;
    xt[i] = gx * gt;
    yt[i] = gy * gt;
}

__kernel void lk_step(__global const float *xx, __global const float *xy, __global const float *yy,
                      __global const float *xt, __global const float *yt, float ridge, float limit,
                      __global float *flow, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float u = flow[2 * i], v = flow[2 * i + 1];
    if (!(isfinite(u) && isfinite(v))) return;
    float a = xx[i] + ridge, b = xy[i], c = yy[i] + ridge;
    float p = xt[i], q = yt[i];
    float det = a * c - b * b;  /* > 0: a and c exceed b's share by ridge (Cauchy-Schwarz on the sums) */
    float du = -(c * p - b * q) / det, dv = -(a * q - b * p) / det;
    flow[2 * i] = u + clamp(du, -limit, limit);
    flow[2 * i + 1] = v + clamp(dv, -limit, limit);
}
