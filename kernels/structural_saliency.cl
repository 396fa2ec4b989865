/* structural_saliency.cl: Sha'ashua and Ullman's saliency network (vmcl/group/structural_saliency.py).
 * Seed section "Saliency, grouping, and segmentation".
 *
 * Elements: one per pixel p and direction k (the 8 neighbour steps of curves.cl: E, NE, N, NW, W, SW, S,
 * SE), the oriented piece from p towards p + step k, stored as planes: element (x, y, k) at
 * IDX3(x, y, k, W, H). An element is actual where p and its neighbour k are linked edge pixels, virtual
 * (a gap) elsewhere. Each iteration every element takes the best continuation among the three elements
 * that leave its end p + step k within 45 degrees of it:
 *     E'(i) = sigma(i) + rho(i) max_j f(i, j) E(j)
 * sigma: the element's own strength (0 for virtual), rho: 1 for actual, the gap attenuation for virtual;
 * f(i, j) = exp(-curvature_scale * 2 alpha tan(alpha / 2) / ds), alpha the turn from i to j and ds the
 * element's length, the discrete form of the integral of squared curvature; a turn into or out of a
 * gap is counted from the edge of the virtual element's 45-degree sector (within a gap, in full). After n iterations E(i) is the saliency of the best curve of n elements that
 * starts with i.
 */
#include "vmcl.h"

__constant int DX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
__constant int DY[8] = {0, -1, -1, -1, 0, 1, 1, 1};
/* The screen angle of step k (y downwards): atan2(DY, DX). */
__constant float STEP_ANGLE[8] = {0.0f, -M_PI_4_F, -M_PI_2_F, -3.0f * M_PI_4_F, M_PI_F, 3.0f * M_PI_4_F,
                                  M_PI_2_F, M_PI_4_F};

/* The direction of element (p, k): an actual element follows the curve's tangent at p (of the two
 * senses, the one within 90 degrees of the step), a virtual one its step. */
inline float element_angle(__global const uchar *links, __global const float *tangent, size_t p, int k)
{
    float step = STEP_ANGLE[k];
    float t = tangent[p];
    if (!(links[p] & (1 << k)) || isnan(t)) return step;
    float d = t - step;
    d -= 2.0f * M_PI_F * rint(d / (2.0f * M_PI_F));
    return fabs(d) > M_PI_2_F ? t + M_PI_F : t;
}

inline float turn(float a, float b)
{
    float d = fabs(a - b);
    d -= 2.0f * M_PI_F * floor(d / (2.0f * M_PI_F));
    return d > M_PI_F ? 2.0f * M_PI_F - d : d;
}

/* Strength 1 on every edge pixel, 0 elsewhere: the default sigma. */
__kernel void unit_strength(__global const uchar *edges, __global float *strength, long n)
{
    long i = get_global_id(0);
    if (i < n) strength[i] = edges[i] ? 1.0f : 0.0f;
}

/* The static part of the network: each element's sigma and rho, and its couplings to the three
 * elements it may continue into (f = 0 past the border or for a turn of 90 degrees or more). */
__kernel void prepare(__global const uchar *links, __global const float *tangent, __global const float *strength,
                      __global float *sigma, __global float *rho, __global float *coupling,
                      float gap_attenuation, float curvature_scale, int W, int H)
{
    int x = get_global_id(0), y = get_global_id(1), k = get_global_id(2);
    if (x >= W || y >= H) return;
    size_t p = (size_t)y * W + x;
    size_t e = IDX3(x, y, k, W, H);
    size_t plane = (size_t)W * H * 8;
    int actual = (links[p] >> k) & 1;
    int qx = x + DX[k], qy = y + DY[k];
    sigma[e] = actual ? 0.5f * (strength[p] + strength[(size_t)qy * W + qx]) : 0.0f;
    rho[e] = actual ? 1.0f : gap_attenuation;
    float ds = (k & 1) ? M_SQRT2_F : 1.0f;
    float own = element_angle(links, tangent, p, k);
    int inside = qx >= 0 && qy >= 0 && qx < W && qy < H;
    for (int c = 0; c < 3; c++) {
        int kk = (k + c + 7) & 7;
        float f = 0.0f;
        if (inside) {
            size_t q = (size_t)qy * W + qx;
            float alpha = turn(own, element_angle(links, tangent, q, kk));
            /* A virtual element stands for any direction within half a step's sector of its own (its
             * direction is only known to the grid's 45 degrees), so a turn into or out of a gap is
             * counted from the sector's edge. */
            /* Into or out of a gap only: within one, turns cost in full, lest a curve loop back through
             * empty space and count its own pixels again. */
            if (actual != ((links[q] >> kk) & 1)) alpha = fmax(0.0f, alpha - M_PI_F / 8.0f);
            f = alpha < M_PI_2_F ? exp(-curvature_scale * 2.0f * alpha * tan(0.5f * alpha) / ds) : 0.0f;
        }
        coupling[c * plane + e] = f;
    }
}

/* One iteration of the network over every element. */
__kernel void iterate(__global const float *saliency, __global const float *sigma, __global const float *rho,
                      __global const float *coupling, __global float *out, int W, int H)
{
    int x = get_global_id(0), y = get_global_id(1), k = get_global_id(2);
    if (x >= W || y >= H) return;
    size_t e = IDX3(x, y, k, W, H);
    size_t plane = (size_t)W * H * 8;
    int qx = min(max(x + DX[k], 0), W - 1), qy = min(max(y + DY[k], 0), H - 1);
    float best = 0.0f;
    for (int c = 0; c < 3; c++) {
        int kk = (k + c + 7) & 7;
        best = fmax(best, coupling[c * plane + e] * saliency[IDX3(qx, qy, kk, W, H)]);
    }
    out[e] = sigma[e] + rho[e] * best;
}

/* A pixel's saliency: the best curve through it, its best element ahead plus the best of the three
 * elements leaving it the opposite way (within 45 degrees of straight back), counting the pixel's own
 * strength once. */
__kernel void pixel_saliency(__global const float *saliency, __global float *out, int W, int H)
{
    int x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float best = 0.0f;
    for (int k = 0; k < 8; k++) {
        float ahead = saliency[IDX3(x, y, k, W, H)];
        float back = 0.0f;
        for (int c = 3; c <= 5; c++) back = fmax(back, saliency[IDX3(x, y, (k + c) & 7, W, H)]);
        best = fmax(best, ahead + back);
    }
    out[(size_t)y * W + x] = best;
}
