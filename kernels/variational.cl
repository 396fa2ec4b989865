/* variational.cl: the variational refinement of a dense flow (vmcl/early/variational.py).
 *
 * The energy of a step w = (du, dv) about the current flow (u, v):
 *   sum_p delta psi((Ix du + Iy dv + Iz)^2)
 *       + gamma psi((Ixx du + Ixy dv + Ixz)^2 + (Ixy du + Iyy dv + Iyz)^2)
 *       + alpha psi(|grad(u + du)|^2 + |grad(v + dv)|^2),   psi(s) = sqrt(s + eps^2),
 * brightness constancy and gradient constancy linearised about the flow, and a robust smoothness of the
 * whole flow (Brox, Bruhn, Papenberg and Weickert, ECCV 2004). Lagged robust weights make each fixed-point
 * iteration a linear system, relaxed by red-black successive over-relaxation: a continuous MRF whose sites
 * each update from their four neighbours, one processor per pixel.
 *
 *   vr_terms    frame 1 read where the flow points (bilinearly) and the derivatives the energy needs, each
 *               the mean of frame 0's at x and frame 1's at x + (u, v) (the symmetric form; central
 *               differences, the border pixel repeated outwards): Ix, Iy, Iz,
 *               Ixx, Ixy, Iyy, Ixz, Iyz, eight planes, the brightness in the units `gain` carries it to;
 *               zero where the flow is not finite or leaves frame 1 (no data: the smoothness fills in)
 *   vr_weights  the robust weights at the current step: each pixel's 2 x 2 data matrix and right-hand side
 *               and its smoothness weight (alpha psi' of the flow's gradient), one float8 per pixel
 *               (a11, a12, a22, b1, b2, smoothness, unused, unused): one read gives a pixel its system
 *               A link's weight in the relaxation is the mean of its two ends' smoothness weights (each
 *               taken from its own forward differences), which keeps the system symmetric.
 *   vr_relax    one half-sweep of the over-relaxation over the pixels of one colour ((x + y) % 2 == parity),
 *               one work-item per pixel of that colour
 *   vr_apply    the step added to the flow
 *
 * Layout: frames and planes row-major W x H float; the flow and the step H x W x 2 interleaved (u, v).
 * One work-item per pixel.
 */
#include "vmcl.h"
#include "sampling.h"

__kernel void vr_terms(__global const float *f0, __global const float *f1, __global const float *flow,
                       float gain, __global float *terms, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x, n = W * H;
    float u = flow[2 * i], v = flow[2 * i + 1];
    float sx = (float)x + u, sy = (float)y + v;
    float t[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    if (isfinite(u) && isfinite(v) && sx >= 0.0f && sy >= 0.0f && sx <= (float)(W - 1) && sy <= (float)(H - 1)) {
        long xl = max(x - 1, 0L), xr = min(x + 1, W - 1), yu = max(y - 1, 0L), yd = min(y + 1, H - 1);
        float c0 = f0[i];
        float l0 = f0[y * W + xl], r0 = f0[y * W + xr], u0 = f0[yu * W + x], d0 = f0[yd * W + x];
        float ul0 = f0[yu * W + xl], ur0 = f0[yu * W + xr], dl0 = f0[yd * W + xl], dr0 = f0[yd * W + xr];
        float c1 = bilinear_clamped(f1, sx, sy, W, H);
        float l1 = bilinear_clamped(f1, sx - 1.0f, sy, W, H), r1 = bilinear_clamped(f1, sx + 1.0f, sy, W, H);
        float u1 = bilinear_clamped(f1, sx, sy - 1.0f, W, H), d1 = bilinear_clamped(f1, sx, sy + 1.0f, W, H);
        float ul1 = bilinear_clamped(f1, sx - 1.0f, sy - 1.0f, W, H);
        float ur1 = bilinear_clamped(f1, sx + 1.0f, sy - 1.0f, W, H);
        float dl1 = bilinear_clamped(f1, sx - 1.0f, sy + 1.0f, W, H);
        float dr1 = bilinear_clamped(f1, sx + 1.0f, sy + 1.0f, W, H);
        float x0 = 0.5f * (r0 - l0), y0 = 0.5f * (d0 - u0), x1 = 0.5f * (r1 - l1), y1 = 0.5f * (d1 - u1);
        t[0] = 0.5f * (x0 + x1);
        t[1] = 0.5f * (y0 + y1);
        t[2] = c1 - c0;
        t[3] = 0.5f * ((r0 - 2.0f * c0 + l0) + (r1 - 2.0f * c1 + l1));
        t[4] = 0.125f * ((dr0 - ur0 - dl0 + ul0) + (dr1 - ur1 - dl1 + ul1));
        t[5] = 0.5f * ((d0 - 2.0f * c0 + u0) + (d1 - 2.0f * c1 + u1));
        t[6] = x1 - x0;
        t[7] = y1 - y0;
    }
    for (int k = 0; k < 8; k++) terms[k * n + i] = gain * t[k];
}

__kernel void vr_weights(__global const float *terms, __global const float *flow, __global const float *step,
                         float delta, float gamma, float alpha, float eps2, __global float8 *system, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x, n = W * H;
    float ix = terms[i], iy = terms[n + i], iz = terms[2 * n + i];
    float ixx = terms[3 * n + i], ixy = terms[4 * n + i], iyy = terms[5 * n + i];
    float ixz = terms[6 * n + i], iyz = terms[7 * n + i];
    float du = step[2 * i], dv = step[2 * i + 1];
    float r = ix * du + iy * dv + iz;
    float gx = ixx * du + ixy * dv + ixz, gy = ixy * du + iyy * dv + iyz;
    /* psi'(s) = 1 / (2 sqrt(s + eps^2)), times each term's weight */
    float wd = delta * 0.5f * rsqrt(r * r + eps2);
    float wg = gamma * 0.5f * rsqrt(gx * gx + gy * gy + eps2);
    /* the whole flow's gradient (forward differences; none past the border, none to a pixel without flow) */
    float u = flow[2 * i] + du, v = flow[2 * i + 1] + dv;
    float s = 0.0f;
    long next[2] = {x + 1 < W ? i + 1 : -1, y + 1 < H ? i + W : -1};
    for (int k = 0; k < 2; k++) {
        long j = next[k];
        if (j < 0) continue;
        float a = flow[2 * j] + step[2 * j] - u, b = flow[2 * j + 1] + step[2 * j + 1] - v;
        if (isfinite(a) && isfinite(b)) s += a * a + b * b;
    }
    /* a pixel without a flow links to none */
    float smooth = isfinite(u) && isfinite(v) ? alpha * 0.5f * rsqrt(s + eps2) : 0.0f;
    system[i] = (float8)(wd * ix * ix + wg * (ixx * ixx + ixy * ixy), wd * ix * iy + wg * (ixx * ixy + ixy * iyy),
                         wd * iy * iy + wg * (ixy * ixy + iyy * iyy), wd * ix * iz + wg * (ixx * ixz + ixy * iyz),
                         wd * iy * iz + wg * (ixy * ixz + iyy * iyz), smooth, 0.0f, 0.0f);
}

/* Work-item (gx, y) updates the pixel x = 2 gx + ((y + parity) & 1) of its colour on row y. */
__kernel void vr_relax(__global const float *flow, __global float *step, __global const float8 *system,
                       float omega, int parity, long W, long H)
{
    long y = get_global_id(1), x = 2 * (long)get_global_id(0) + ((y + parity) & 1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float u = flow[2 * i], v = flow[2 * i + 1];
    if (!(isfinite(u) && isfinite(v))) return;  /* keeps its flow, as it came */
    float8 own = system[i];
    float total = 0.0f, su = 0.0f, sv = 0.0f;
    /* a link's weight is the mean of its two ends' smoothness weights */
    long nb[4] = {x > 0 ? i - 1 : -1, x + 1 < W ? i + 1 : -1, y > 0 ? i - W : -1, y + 1 < H ? i + W : -1};
    for (int k = 0; k < 4; k++) {
        long j = nb[k];
        if (j < 0) continue;
        float fu = flow[2 * j], fv = flow[2 * j + 1];
        float w = 0.5f * (own.s5 + system[j].s5);
        if (!(isfinite(fu) && isfinite(fv) && w > 0.0f)) continue;
        total += w;
        su += w * (fu + step[2 * j] - u);
        sv += w * (fv + step[2 * j + 1] - v);
    }
    float du = step[2 * i], dv = step[2 * i + 1];
    float d1 = own.s0 + total, d2 = own.s2 + total;
    if (d1 > 0.0f) du = (1.0f - omega) * du + omega * (su - own.s3 - own.s1 * dv) / d1;
    if (d2 > 0.0f) dv = (1.0f - omega) * dv + omega * (sv - own.s4 - own.s1 * du) / d2;
    step[2 * i] = du;
    step[2 * i + 1] = dv;
}

__kernel void vr_apply(__global float *flow, __global const float *step, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    flow[2 * i] += step[2 * i];
    flow[2 * i + 1] += step[2 * i + 1];
}
