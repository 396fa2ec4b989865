/* texture.cl: texton density, seed section "Texture" (a simplified, parallel Voorhees-Poggio). One
 * work-item per pixel over a (W, H) grid; ids past the field idle. Borders clamp.
 *
 *   textons           fine-scale blobs of the Laplacian of a Gaussian that the coarse scale does not see
 *   window_mean       blob counts over the (2r+1)^2 window (from box_sum) divided by the window's pixels
 *                     inside the field: the share of the window covered by blobs
 *   density_gradient  difference of the densities of the two adjacent windows across each pixel's right
 *                     and lower sites, its magnitude and dominant axis
 *   texture_edges     non-maximum suppression along the dominant axis, then the threshold
 */
#include "vmcl.h"

#define AT(f, xx, yy) ((f)[(yy) * W + (xx)])

/* A fine blob pixel has a scale-normalised response (sigma^2 times the LoG) beyond t of either sign;
 * it is dropped when a coarse blob of the same sign covers it or one of its 8 neighbours. The
 * neighbourhood matters at contrast steps: near the step the fine response rises sigma_c / sigma_f
 * times faster than the coarse one, so a sliver of fine strip lies just outside the coarse strip. */
__kernel void textons(__global const float *fine, __global const float *coarse, __global int *blobs,
                      float fine_scale, float coarse_scale, float t, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float f = fine_scale * AT(fine, x, y);
    int sign = f > t ? 1 : (f < -t ? -1 : 0);
    int covered = 0;
    for (long dy = -1; dy <= 1; dy++) {
        long yy = clamp(y + dy, 0L, H - 1);
        for (long dx = -1; dx <= 1; dx++) {
            float c = coarse_scale * AT(coarse, clamp(x + dx, 0L, W - 1), yy);
            covered |= (sign > 0 && c > t) || (sign < 0 && c < -t);
        }
    }
    AT(blobs, x, y) = sign != 0 && !covered;
}

__kernel void window_mean(__global const int *sums, __global float *density, long r, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long nx = min(x + r, W - 1) - max(x - r, 0L) + 1, ny = min(y + r, H - 1) - max(y - r, 0L) + 1;
    AT(density, x, y) = (float)AT(sums, x, y) / (float)(nx * ny);
}

/* Across the site between x and x + 1, the window centred at x + r + 1 covers [x + 1, x + 2r + 1] and
 * the one at x - r covers [x - 2r, x]: their difference peaks where a boundary between two densities
 * falls on the site and falls off linearly either side (a box-filtered ramp would be flat on top).
 * Centres beyond the field clamp to its edge. axis: 1 where the x difference dominates. */
__kernel void density_gradient(__global const float *density, __global float *magnitude, __global uchar *axis,
                               long r, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float gx = AT(density, min(x + r + 1, W - 1), y) - AT(density, max(x - r, 0L), y);
    float gy = AT(density, x, min(y + r + 1, H - 1)) - AT(density, x, max(y - r, 0L));
    AT(magnitude, x, y) = sqrt(gx * gx + gy * gy);
    AT(axis, x, y) = fabs(gx) >= fabs(gy);
}

/* A candidate is a maximum along its dominant axis (strictly above the neighbour before it, at least
 * the one after, so a two-pixel tie keeps one) whose magnitude exceeds max(thr[0], floor), or floor alone
 * when `fixed` (a threshold from the host only; thr is then not read). An argument, not a define: the
 * file is one build on a first run. */
__kernel void texture_edges(__global const float *magnitude, __global const uchar *axis,
                            __global const float *thr, __global uchar *edges, float floor_threshold,
                            long W, long H, int fixed)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float m = AT(magnitude, x, y);
    float before, after;
    if (AT(axis, x, y)) {
        before = AT(magnitude, max(x - 1, 0L), y);
        after = AT(magnitude, min(x + 1, W - 1), y);
    } else {
        before = AT(magnitude, x, max(y - 1, 0L));
        after = AT(magnitude, x, min(y + 1, H - 1));
    }
    float t = fixed ? floor_threshold : fmax(thr[0], floor_threshold);
    AT(edges, x, y) = m > before && m >= after && m > t;
}
