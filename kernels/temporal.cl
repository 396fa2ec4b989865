/* temporal.cl: continuity in time, seed section "Fast vision: The role of time smoothness" (vmcl/temporal.py).
 *
 *   predict   the previous frame's restored field carried to this frame along the previous flow, the
 *             information it carries (a Kalman prediction: the information w becomes w m / (m + w), m
 *             the memory, so old evidence fades), and the temporal line process: time is broken where
 *             the brightness at the carried position disagrees with this frame's by more than the
 *             tolerance, or where the position left the image. The frame's first launch tests the
 *             brightness and writes `broken`; the cues' launches (`tested`) read it, the same for all
 *   fuse      the cue's new measurement and the prediction as one data term: the information-weighted
 *             mean, with the information summed (the Kalman update, which the MRF's data term then holds),
 *             except where the two differ by more than the cue's jump (time broken for that cue), and the
 *             MRF's warm start: the prediction where it was used
 *
 * Layout: fields are H x W x NCOMP interleaved (NCOMP 1..4), one work-item per pixel. The carried position
 * of pixel x is x - u(x), u the previous frame's flow at x: the flow maps the previous frame's pixels onto
 * this one, and for flow that varies slowly the pixel that lands on x came from there; where that fails
 * (at motion boundaries) the brightness test breaks time. Defines: NCOMP; NEAREST (1: the field is
 * piecewise constant and is read at the nearest pixel, 0: bilinearly where all four neighbours hold a
 * value, else at the nearest).
 */
#include "vmcl.h"

inline float bilinear(__global const float *image, float x, float y, long W, long H)
{
    long x0 = (long)floor(x), y0 = (long)floor(y);
    long x1 = min(x0 + 1, W - 1), y1 = min(y0 + 1, H - 1);
    float ax = x - (float)x0, ay = y - (float)y0;
    float top = mix(image[y0 * W + x0], image[y0 * W + x1], ax);
    float bottom = mix(image[y1 * W + x0], image[y1 * W + x1], ax);
    return mix(top, bottom, ay);
}

/* The field's component c at (x, y): bilinear over the four neighbours when they all hold a value. */
inline float carried(__global const float *field, float x, float y, int c, long W, long H)
{
    long nx = (long)round(x), ny = (long)round(y);
    float nearest = field[(ny * W + nx) * NCOMP + c];
#if NEAREST
    return nearest;
#else
    long x0 = (long)floor(x), y0 = (long)floor(y);
    long x1 = min(x0 + 1, W - 1), y1 = min(y0 + 1, H - 1);
    float a = field[(y0 * W + x0) * NCOMP + c], b = field[(y0 * W + x1) * NCOMP + c];
    float d = field[(y1 * W + x0) * NCOMP + c], e = field[(y1 * W + x1) * NCOMP + c];
    if (!(isfinite(a) && isfinite(b) && isfinite(d) && isfinite(e))) return nearest;
    float ax = x - (float)x0, ay = y - (float)y0;
    return mix(mix(a, b, ax), mix(d, e, ax), ay);
#endif
}

__kernel void predict(__global const float *field, __global const float *information,
                      __global const float *flow, int has_flow,
                      __global const float *grey_before, __global const float *grey_now,
                      float tolerance, float memory, __global float *prediction, __global float *weight,
                      __global uchar *broken, int tested, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float sx = (float)x, sy = (float)y;
    if (has_flow) {
        float u = flow[2 * i], v = flow[2 * i + 1];
        if (isfinite(u) && isfinite(v)) {
            sx -= u;
            sy -= v;
        }
    }
    int inside = sx >= 0.0f && sy >= 0.0f && sx <= (float)(W - 1) && sy <= (float)(H - 1);
    int agrees = inside && (tested ? !broken[i]
                                   : fabs(bilinear(grey_before, sx, sy, W, H) - grey_now[i]) <= tolerance);
    float w = 0.0f;
    for (int c = 0; c < NCOMP; ++c) prediction[i * NCOMP + c] = NAN;
    if (agrees) {
        int complete = 1;
        for (int c = 0; c < NCOMP; ++c) {
            float value = carried(field, sx, sy, c, W, H);
            prediction[i * NCOMP + c] = value;
            complete &= isfinite(value);
        }
        float info = information[(long)round(sy) * W + (long)round(sx)];
        if (complete && info > 0.0f) w = info * memory / (memory + info);
        if (!complete)
            for (int c = 0; c < NCOMP; ++c) prediction[i * NCOMP + c] = NAN;
    }
    weight[i] = w;
    if (!tested) broken[i] = (uchar)!agrees;
}

__kernel void fuse(__global const float *data, __global const float *confidence, int has_confidence,
                   __global const float *prediction, __global const float *weight, int has_prediction, float gain,
                   float jump, __global float *fused, __global float *information, __global float *start,
                   long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float c = has_confidence ? confidence[i] : 1.0f;
    int measured = 1;
    for (int k = 0; k < NCOMP; ++k)
        if (!isfinite(data[i * NCOMP + k])) measured = 0;
    if (!measured) c = 0.0f;
    float t = has_prediction ? gain * weight[i] : 0.0f;
    /* Time is broken for this cue where the new measurement and the carried value differ by more than
     * the jump (the surface or its motion changed): the pixel keeps the measurement alone. */
    if (t > 0.0f && measured && c > 0.0f) {
        float d2 = 0.0f;
        for (int k = 0; k < NCOMP; ++k) {
            float d = data[i * NCOMP + k] - prediction[i * NCOMP + k];
            d2 += d * d;
        }
        if (d2 > jump * jump) t = 0.0f;
    }
    float total = c + t;
    for (int k = 0; k < NCOMP; ++k) {
        float value = NAN;
        if (total > 0.0f)
            value = ((c > 0.0f ? c * data[i * NCOMP + k] : 0.0f)
                     + (t > 0.0f ? t * prediction[i * NCOMP + k] : 0.0f)) / total;
        fused[i * NCOMP + k] = value;
        start[i * NCOMP + k] = t > 0.0f ? prediction[i * NCOMP + k] : NAN;
    }
    information[i] = total;
}
