/* verification.cl: the exact distance transform of an edge map and the support of posed model points
 * (vmcl/recognize/verification.py).
 *
 * Distance transform (Felzenszwalb and Huttenlocher's two passes): one work-item per column finds each
 * pixel's nearest edge pixel in its column; one work-item per row then takes the lower envelope of the
 * parabolas (x - x')^2 + (y - row(x'))^2 over the columns x', giving every pixel its nearest edge pixel
 * in the image (its flat address; -1 where the image has no edge pixel).
 *
 * Support: one work-item per (candidate, model point). The point is carried into the image by the
 * candidate's 2 x 3 affine matrix, or its 3 x 3 homography; it reads its nearest edge pixel, the distance
 * to it, and the angle between its own carried tangent and the edge's tangent (modulo pi; 0 where the
 * edge's tangent is unknown). Points that land outside the image are marked so.
 */
#include "vmcl.h"

__kernel void column_nearest(__global const uchar *edges, __global int *rows, int W, int H)
{
    int x = get_global_id(0);
    if (x >= W) return;
    int last = -1;
    for (int y = 0; y < H; y++) {
        if (edges[(long)y * W + x]) last = y;
        rows[(long)y * W + x] = last;
    }
    last = -1;
    for (int y = H - 1; y >= 0; y--) {
        long i = (long)y * W + x;
        if (edges[i]) last = y;
        int above = rows[i];
        if (last >= 0 && (above < 0 || last - y < y - above)) rows[i] = last;
    }
}

__kernel void row_envelope(__global const int *rows, __global int *nearest, __global int *hull, __global float *bounds,
                           int W, int H)
{
    int y = get_global_id(0);
    if (y >= H) return;
    __global const int *row = rows + (long)y * W;
    __global int *v = hull + (long)y * W;
    __global float *z = bounds + (long)y * (W + 1);
    int k = -1;
    for (int q = 0; q < W; q++) {
        if (row[q] < 0) continue;
        float dq = (float)(y - row[q]);
        float fq = dq * dq + (float)q * (float)q;
        while (k >= 0) {
            int p = v[k];
            float dp = (float)(y - row[p]);
            float fp = dp * dp + (float)p * (float)p;
            float s = (fq - fp) / (2.0f * (float)(q - p));
            if (s > z[k]) {
                k++;
                v[k] = q;
                z[k] = s;
                break;
            }
            k--;
        }
        if (k < 0) {
            k = 0;
            v[0] = q;
            z[0] = -INFINITY;
        }
    }
    long base = (long)y * W;
    if (k < 0) {
        for (int x = 0; x < W; x++) nearest[base + x] = -1;
        return;
    }
    int j = 0;
    for (int x = 0; x < W; x++) {
        while (j < k && z[j + 1] < (float)x) j++;
        int q = v[j];
        nearest[base + x] = row[q] * W + q;
    }
}

/* status: 0 inside the image, 1 outside (or no edge pixel anywhere). */
__kernel void support(__global const int *nearest, __global const float *tangent_map, __global const float2 *points,
                      __global const float *tangents, __global const int *point_of_item,
                      __global const int *candidate_of_item, __global const float *transforms,
                      __global float4 *found, __global uchar *status, int items, int W, int H)
{
    int i = get_global_id(0);
    if (i >= items) return;
    int k = point_of_item[i];
    __global const float *m = transforms + 9 * (long)candidate_of_item[i];
    float2 p = points[k];
    float w = m[6] * p.x + m[7] * p.y + m[8];
    float x = (m[0] * p.x + m[1] * p.y + m[2]) / w;
    float y = (m[3] * p.x + m[4] * p.y + m[5]) / w;
    int cx = (int)floor(x + 0.5f), cy = (int)floor(y + 0.5f);
    if (!(w > 0.0f) || cx < 0 || cy < 0 || cx >= W || cy >= H) {
        status[i] = 1;
        found[i] = (float4)(0.0f, 0.0f, INFINITY, 0.0f);
        return;
    }
    int q = nearest[(long)cy * W + cx];
    if (q < 0) {
        status[i] = 1;
        found[i] = (float4)(0.0f, 0.0f, INFINITY, 0.0f);
        return;
    }
    float qx = (float)(q % W), qy = (float)(q / W);
    /* The tangent carried by the map's derivative at p (the homography's, or the affine part). */
    float t = tangents[k];
    float diff = 0.0f;
    float e = tangent_map[q];
    if (!isnan(t) && !isnan(e)) {
        float dx = cos(t), dy = sin(t);
        float jx = ((m[0] - x * m[6]) * dx + (m[1] - x * m[7]) * dy) / w;
        float jy = ((m[3] - y * m[6]) * dx + (m[4] - y * m[7]) * dy) / w;
        float a = atan2(jy, jx) - e;
        a = a - M_PI_F * floor(a / M_PI_F);  /* modulo pi, in [0, pi) */
        diff = fmin(a, M_PI_F - a);
    }
    status[i] = 0;
    found[i] = (float4)(qx, qy, hypot(x - qx, y - qy), diff);
}
