/* registration.cl, driven by vmcl/early/registration.py.
 * Warping an image by a stored table, seed section "Stereo" (Memory-based registration and
 * calibration): "the right image is warped according to the pre-stored addresses by sending each pixel
 * ... to the processor specified in the table". Every output pixel gets (a router read of) the four
 * pixels around its table address, weighted bilinearly.
 *
 * The table holds, per output pixel, the (x, y) position in the source image to read, as float32 pairs.
 */
#include "vmcl.h"

/* out[y, x, c] = bilinear sample of image at table[y, x]; NaN where the four pixels around that
 * position are not all inside the image (nothing is extrapolated). */
__kernel void warp_bilinear(__global const float *image, __global const float *table, __global float *out,
                            long W, long H, long C)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    float sx = table[2 * i], sy = table[2 * i + 1];
    float fx = floor(sx), fy = floor(sy);
    float ax = sx - fx, ay = sy - fy;
    /* A position exactly on the last row or column needs no neighbour beyond it. The test is made in
     * float, before any conversion, so a NaN, infinite or huge position never becomes an address. */
    int step_x = ax > 0.0f, step_y = ay > 0.0f;
    int inside = fx >= 0.0f && fy >= 0.0f && fx + (float)step_x <= (float)(W - 1)
                 && fy + (float)step_y <= (float)(H - 1);
    long x0 = inside ? (long)fx : 0, y0 = inside ? (long)fy : 0, x1 = x0 + step_x, y1 = y0 + step_y;
    for (long c = 0; c < C; c++) {
        float v = NAN;
        if (inside) {
            float a = image[(y0 * W + x0) * C + c], b = image[(y0 * W + x1) * C + c];
            float d = image[(y1 * W + x0) * C + c], e = image[(y1 * W + x1) * C + c];
            /* A neighbour of weight 0 is left out rather than multiplied by 0, so an infinite
             * pixel does not turn the samples on its neighbours' grid lines into NaN. */
            float top = ax > 0.0f ? (1.0f - ax) * a + ax * b : a;
            float bottom = ax > 0.0f ? (1.0f - ax) * d + ax * e : d;
            v = ay > 0.0f ? (1.0f - ay) * top + ay * bottom : top;
        }
        out[i * C + c] = v;
    }
}
