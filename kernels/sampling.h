/* sampling.h: reading a float image between its pixels.
 *
 * bilinear_clamped: the bilinear interpolation of a row-major W x H float image at (fx, fy), the position
 * first held inside the image (its border pixels repeat outwards, as the filters' borders do).
 */
#ifndef VMCL_SAMPLING_H
#define VMCL_SAMPLING_H

inline float bilinear_clamped(__global const float *f, float fx, float fy, long W, long H)
{
    fx = clamp(fx, 0.0f, (float)(W - 1));
    fy = clamp(fy, 0.0f, (float)(H - 1));
    long x0 = (long)fx, y0 = (long)fy;
    long x1 = min(x0 + 1, W - 1), y1 = min(y0 + 1, H - 1);
    float ax = fx - (float)x0, ay = fy - (float)y0;
    return (1.0f - ay) * ((1.0f - ax) * f[y0 * W + x0] + ax * f[y0 * W + x1])
           + ay * ((1.0f - ax) * f[y1 * W + x0] + ax * f[y1 * W + x1]);
}

#endif
