/* warp.cl: warping an image by a stored table, seed section "Stereo" (Memory-based registration and
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
    long x0 = (long)fx, y0 = (long)fy;
    float ax = sx - fx, ay = sy - fy;
    /* A position exactly on the last row or column needs no neighbour beyond it. */
    long x1 = ax > 0.0f ? x0 + 1 : x0, y1 = ay > 0.0f ? y0 + 1 : y0;
    int inside = isfinite(sx) && isfinite(sy) && x0 >= 0 && y0 >= 0 && x1 < W && y1 < H;
    for (long c = 0; c < C; c++) {
        float v = NAN;
        if (inside) {
            float a = image[(y0 * W + x0) * C + c], b = image[(y0 * W + x1) * C + c];
            float d = image[(y1 * W + x0) * C + c], e = image[(y1 * W + x1) * C + c];
            v = (1.0f - ay) * ((1.0f - ax) * a + ax * b) + ay * ((1.0f - ax) * d + ax * e);
        }
        out[i * C + c] = v;
    }
}
