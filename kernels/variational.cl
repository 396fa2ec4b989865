/* variational.cl: the variational refinement of a dense flow (vmcl/early/variational.py).
 *
 * The energy of a step w = (du, dv) about the current flow (u, v):
 *   sum_p delta psi((Ix du + Iy dv + Iz)^2)
 *       + gamma psi((Ixx du + Ixy dv + Ixz)^2 + (Ixy du + Iyy dv + Iyz)^2)
 *       + alpha psi(|grad(u + du)|^2 + |grad(v + dv)|^2),   psi(s) = sqrt(s + eps^2),
 * brightness constancy and gradient constancy linearised about the flow, and a robust smoothness of the
 * whole flow (Brox, Bruhn, Papenberg and Weickert, ECCV 2004). Lagged robust weights make each fixed-point
 * iteration a linear system, relaxed by red-black successive over-relaxation on a multigrid: a continuous
 * MRF whose sites each update from their four neighbours, one processor per pixel.
 *
 *   vr_terms    frame 1 read where the flow points (bilinearly) and the derivatives the energy needs, each
 *               the mean of frame 0's at x and frame 1's at x + (u, v) (the symmetric form; central
 *               differences, the border pixel repeated outwards): Ix, Iy, Iz,
 *               Ixx, Ixy, Iyy, Ixz, Iyz, eight planes, the brightness in the units `gain` carries it to;
 *               zero where the flow is not finite or leaves frame 1 (no data: the smoothness fills in)
 *   vr_weights  the robust weights at the current step: each pixel's 2 x 2 data matrix and right-hand side
 *               (with the pull towards a prior flow, beta psi(|(u, v) + w - prior|^2), where one is given),
 *               written into the pixel grid's system (a11, a12, a22, b1, b2, then zeros that vr_links
 *               fills), and its smoothness weight (alpha psi' of the flow's gradient, from its forward
 *               differences) into a plane of its own
 *   vr_links    the iteration's linear system on the pixel grid: each link's weight the mean of its two
 *               ends' smoothness weights (which keeps the system symmetric)
 *   vr_relax    one half-sweep of the over-relaxation over the pixels of one colour ((x + y) % 2 == parity),
 *               one work-item per pixel of that colour, on any level
 *   vr_residual, vr_restrict, vr_prolong
 *               the multigrid's transfers: what the unknown leaves of the right-hand side; the coarser
 *               level's system (2 x 2 blocks) with the residual as its right-hand side; its solution
 *               added back to the finer level's unknown. Relaxation alone needs about as many sweeps as the
 *               smoothness carries a correction pixels far; each coarser level carries it twice as far
 *               per sweep (Bruhn, Weickert et al., IEEE TIP 2005, solve this functional in real time so).
 *   vr_apply    the step added to the flow
 *
 * Layout: frames and planes row-major W x H float; the flow, the step, the unknowns and the residuals
 * H x W x 2 interleaved (u, v); the systems H x W float8.
 * One work-item per pixel of the level it works on (per pixel of one colour for vr_relax, per coarse pixel
 * for vr_restrict).
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
                         __global const float *prior, float beta, float delta, float gamma, float alpha,
                         float eps2, __global float8 *system, __global float *smooth, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x, n = W * H;
    float ix = terms[i], iy = terms[n + i], iz = terms[2 * n + i];
    float ixx = terms[3 * n + i], ixy = terms[4 * n + i], iyy = terms[5 * n + i];
    float ixz = terms[6 * n + i], iyz = terms[7 * n + i];
    float2 d = vload2(i, step);
    float r = ix * d.x + iy * d.y + iz;
    float gx = ixx * d.x + ixy * d.y + ixz, gy = ixy * d.x + iyy * d.y + iyz;
    /* psi'(s) = 1 / (2 sqrt(s + eps^2)), times each term's weight */
    float wd = delta * 0.5f * rsqrt(r * r + eps2);
    float wg = gamma * 0.5f * rsqrt(gx * gx + gy * gy + eps2);
    /* the whole flow's gradient (forward differences; none past the border, none to a pixel without flow) */
    float2 w = vload2(i, flow) + d;
    float s = 0.0f;
    if (x + 1 < W) {
        float2 g = vload2(i + 1, flow) + vload2(i + 1, step) - w;
        if (isfinite(g.x) && isfinite(g.y)) s += dot(g, g);
    }
    if (y + 1 < H) {
        float2 g = vload2(i + W, flow) + vload2(i + W, step) - w;
        if (isfinite(g.x) && isfinite(g.y)) s += dot(g, g);
    }
    /* a pixel without a flow links to none */
    smooth[i] = isfinite(w.x) && isfinite(w.y) ? alpha * 0.5f * rsqrt(s + eps2) : 0.0f;
    /* the pull towards the prior flow (none where it has no value): beta psi(|w - prior|^2) */
    float wp = 0.0f;
    float2 gap = (float2)(0.0f);
    if (beta > 0.0f) {
        float2 p = vload2(i, prior);
        if (isfinite(p.x) && isfinite(p.y)) {
            gap = vload2(i, flow) - p;
            float2 g = gap + d;
            wp = beta * 0.5f * rsqrt(dot(g, g) + eps2);
        }
    }
    system[i] = (float8)(wd * ix * ix + wg * (ixx * ixx + ixy * ixy) + wp,
                         wd * ix * iy + wg * (ixx * ixy + ixy * iyy),
                         wd * iy * iy + wg * (ixy * ixy + iyy * iyy) + wp,
                         wd * ix * iz + wg * (ixx * ixz + ixy * iyz) + wp * gap.x,
                         wd * iy * iz + wg * (ixy * ixz + iyy * iyz) + wp * gap.y, 0.0f, 0.0f, 0.0f);
}

/* The linear system of a fixed-point iteration, on any level of the multigrid: per pixel one float8
 * (a11, a12, a22, ru, rv, right, down, unused), the unknown e = (eu, ev) answering
 *   (a11 + L) eu + a12 ev - sum_q w_q eu_q = ru,   a12 eu + (a22 + L) ev - sum_q w_q ev_q = rv,
 * over the four neighbours q with link weights w_q (a pixel's own right and down links, its left
 * neighbour's right link and its upper neighbour's down link) and L their sum. */

/* The link from a pixel with flow f and smoothness weight sp to pixel j (the mean of the two ends' weights;
 * none to a pixel without flow), its neighbour's flow's pull added to `pull`. */
inline float link_to(long j, float sp, float2 f, __global const float *smooth, __global const float *flow,
                     float2 *pull)
{
    float2 g = vload2(j, flow);
    if (!(isfinite(g.x) && isfinite(g.y))) return 0.0f;
    float w = 0.5f * (sp + smooth[j]);
    *pull += w * (g - f);
    return w;
}

/* The pixel grid's system completed in place (vr_weights left its data terms in it): its links and its
 * right-hand side (minus the data term's, plus the pull of the neighbours' incoming flow on the pixel's). The
 * unknown is the step from the incoming flow. A pixel without flow has no system at all. */
__kernel void vr_links(__global const float *smooth, __global const float *flow, __global float8 *system,
                       long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float2 f = vload2(i, flow);
    if (!(isfinite(f.x) && isfinite(f.y))) {
        system[i] = (float8)(0.0f);
        return;
    }
    float sp = smooth[i];
    float2 pull = (float2)(0.0f);
    float right = x + 1 < W ? link_to(i + 1, sp, f, smooth, flow, &pull) : 0.0f;
    float down = y + 1 < H ? link_to(i + W, sp, f, smooth, flow, &pull) : 0.0f;
    if (x > 0) link_to(i - 1, sp, f, smooth, flow, &pull);
    if (y > 0) link_to(i - W, sp, f, smooth, flow, &pull);
    float8 own = system[i];
    system[i] = (float8)(own.s0, own.s1, own.s2, pull.x - own.s3, pull.y - own.s4, right, down, 0.0f);
}

/* The links' sum and the weighted sum of the neighbours' unknowns. */
inline float link_sums(__global const float *e, __global const float8 *system, long x, long y, long W, long H,
                       float8 own, float2 *sums)
{
    long i = y * W + x;
    float total = own.s5 + own.s6;
    float2 s = (float2)(0.0f);
    if (x + 1 < W) s += own.s5 * vload2(i + 1, e);
    if (y + 1 < H) s += own.s6 * vload2(i + W, e);
    if (x > 0) {
        float w = system[i - 1].s5;
        total += w;
        s += w * vload2(i - 1, e);
    }
    if (y > 0) {
        float w = system[i - W].s6;
        total += w;
        s += w * vload2(i - W, e);
    }
    *sums = s;
    return total;
}

/* One half-sweep of red-black over-relaxation: work-item (gx, y) updates the pixel
 * x = 2 gx + ((y + parity) & 1) of its colour on row y. A pixel with no data and no link keeps its value. */
__kernel void vr_relax(__global float *e, __global const float8 *system, float omega, int parity, long W, long H)
{
    long y = get_global_id(1), x = 2 * (long)get_global_id(0) + ((y + parity) & 1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float8 own = system[i];
    float2 s;
    float total = link_sums(e, system, x, y, W, H, own, &s);
    float2 old = vload2(i, e);
    float du = old.x, dv = old.y;
    float d1 = own.s0 + total, d2 = own.s2 + total;
    if (d1 > 0.0f) du = (1.0f - omega) * du + omega * (own.s3 + s.x - own.s1 * dv) / d1;
    if (d2 > 0.0f) dv = (1.0f - omega) * dv + omega * (own.s4 + s.y - own.s1 * du) / d2;
    vstore2((float2)(du, dv), i, e);
}

/* What the unknown leaves of the right-hand side: r = rhs - A e. */
__kernel void vr_residual(__global const float *e, __global const float8 *system, __global float *residual,
                          long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float8 own = system[i];
    float2 s;
    float total = link_sums(e, system, x, y, W, H, own, &s);
    float2 c = vload2(i, e);
    vstore2((float2)(own.s3 + s.x - (own.s0 + total) * c.x - own.s1 * c.y,
                     own.s4 + s.y - own.s1 * c.x - (own.s2 + total) * c.y), i, residual);
}

/* The coarse level's system, one coarse pixel per 2 x 2 block of fine ones (a single row or column at an odd
 * border), and its unknown set to zero: the correction of the fine unknown that the coarse level solves for,
 * piecewise constant over each block. Data matrices and residuals are summed over the block (the Galerkin
 * product of that piecewise constant transfer); a coarse link sums the fine links that cross between its two
 * blocks, times `link_scale`, which takes out the factor the piecewise-constant transfer puts on a
 * smoothness term (1/2 for a smooth correction: two fine links across a block's side where the coarse
 * difference spans twice the distance). */
__kernel void vr_restrict(__global const float8 *fine, __global const float *residual, __global float8 *coarse,
                          __global float *e, float link_scale, long W, long H, long CW, long CH)
{
    long X = get_global_id(0), Y = get_global_id(1);
    if (X >= CW || Y >= CH) return;
    long x0 = 2 * X, y0 = 2 * Y, x1 = min(x0 + 1, W - 1), y1 = min(y0 + 1, H - 1);
    float8 sum = (float8)(0.0f);
    for (long y = y0; y <= y1; y++) {
        for (long x = x0; x <= x1; x++) {
            long i = y * W + x;
            float8 f = fine[i];
            float2 r = vload2(i, residual);
            sum.s0 += f.s0;
            sum.s1 += f.s1;
            sum.s2 += f.s2;
            sum.s3 += r.x;
            sum.s4 += r.y;
            if (x == x1) sum.s5 += f.s5;  /* the block's right column: its right links leave the block */
            if (y == y1) sum.s6 += f.s6;
        }
    }
    sum.s5 *= link_scale;
    sum.s6 *= link_scale;
    long I = Y * CW + X;
    coarse[I] = sum;
    vstore2((float2)(0.0f), I, e);
}

/* The coarse correction added to each fine pixel of its block. */
__kernel void vr_prolong(__global float *e, __global const float *coarse_e, long W, long H, long CW)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    vstore2(vload2(i, e) + vload2((y / 2) * CW + x / 2, coarse_e), i, e);
}

__kernel void vr_apply(__global float *flow, __global const float *step, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    flow[2 * i] += step[2 * i];
    flow[2 * i + 1] += step[2 * i + 1];
}
