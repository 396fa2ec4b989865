/* labelling.cl: the integration stage's labels by a linear classifier, seed section "Integration via
 * labeling with a linear classifier" (Gamble, Geiger, Weinshall and Poggio). One work-item per pixel
 * over a (W, H) grid; ids past the field idle.
 *
 *   label_features  the classifier's inputs at every pixel: which cues' line processes lie within one
 *                   pixel and whether a brightness edge is on it (the support bits of vmcl.integrate), and
 *                   local measures of the restored fields that tell the physical causes apart (jumps of
 *                   disparity and flow, creases of disparity, steps of log brightness and hue, whiteness
 *                   and brightness for highlights). With CLASSIFY, the same inputs go straight into the
 *                   linear network: each label's support is a weighted sum of them, and a candidate
 *                   pixel (a support bit of CANDIDATE_BITS on it: a line of a cue that ran, or a
 *                   brightness edge) takes the label of largest support,
 *                   which may be "none"; without it, the inputs are written out (fitting, inspection).
 *
 * Defines (from vmcl.labelling, the one place that names them): NF inputs, NC labels; F_<FEATURE NAME>,
 * each input's slot (vmcl.labelling.SLOT_DEFINES); the support bits
 * BIT_STEREO, BIT_MOTION, BIT_COLOUR, BIT_TEXTURE, BIT_BRIGHTNESS; HAS_STEREO, HAS_MOTION, HAS_COLOUR
 * (which restored fields exist; the inputs of a missing one are 0, whiteness included, which needs
 * colour); RGB (the image has three channels); CANDIDATE_BITS; CODES (the outputs' label codes);
 * HAS_PROBABILITY (with CLASSIFY: the image's probability of boundary is given, and the strength
 * starts from it).
 * Fields: image float32 (H, W) or (H, W, 3) in [0, 1]; disparity, hue float32 (H, W); flow float32
 * (H, W, 2); NaN values (hue outside its valid range) are skipped by the window ranges and the crease.
 */

#define CLIPPED(v, hi) fmin((float)(v), (float)(hi))

#if CLASSIFY
__constant uchar codes[NC] = {CODES};  /* the vmcl.scenes.Label code of each output */
#endif

/* max - min of one channel of a field over the (2r+1)^2 window, clamped at the borders, NaN skipped. */
inline float window_range(__global const float *f, int channels, int c, long x, long y, int r, long W, long H)
{
    float lo = INFINITY, hi = -INFINITY;
    for (long dy = -r; dy <= r; dy++) {
        long yy = clamp(y + dy, 0L, H - 1);
        for (long dx = -r; dx <= r; dx++) {
            float v = f[(yy * W + clamp(x + dx, 0L, W - 1)) * channels + c];
            if (isnan(v)) continue;
            lo = fmin(lo, v);
            hi = fmax(hi, v);
        }
    }
    return hi >= lo ? hi - lo : 0.0f;
}

inline float grey_at(__global const float *image, long i)
{
#if RGB
    return (image[3 * i] + image[3 * i + 1] + image[3 * i + 2]) * (1.0f / 3.0f);
#else
    return image[i];
#endif
}

/* The largest second difference of disparity at a spacing of 3 px, across or along the rows: where a
 * surface folds, the disparity's slope changes. */
inline float crease_at(__global const float *d, long x, long y, long W, long H)
{
    float c = d[y * W + x];
    float across = d[y * W + clamp(x - 3, 0L, W - 1)] - 2.0f * c + d[y * W + clamp(x + 3, 0L, W - 1)];
    float along = d[clamp(y - 3, 0L, H - 1) * W + x] - 2.0f * c + d[clamp(y + 3, 0L, H - 1) * W + x];
    return fmax(fabs(across), fabs(along));
}

__kernel void label_features(__global const uchar *support, __global const float *image,
                             __global const float *disparity, __global const float *flow,
                             __global const float *hue,
#if CLASSIFY
                             __constant const float *weights, __global const float *image_probability,
                             __global uchar *labels, __global float *strength,
#else
                             __global float *features,
#endif
                             long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
#if CLASSIFY
    /* Only candidates are labelled: the others (most pixels) skip the inputs. */
    float seen = HAS_PROBABILITY ? image_probability[i] : 0.0f;
    if (!(support[i] & CANDIDATE_BITS)) {
        labels[i] = 0;
        strength[i] = seen;
        return;
    }
#endif
    float in[NF];
    for (int k = 0; k < NF; k++) in[k] = 0.0f;

    int near = 0;  /* the support bits within one pixel */
    /* The log brightness steps are the logs of the grey's extremes over each window (the log rises with the
     * grey): four logs a pixel where one a window pixel took most of the kernel's time. */
    float lo3 = INFINITY, hi3 = -INFINITY, lo5 = INFINITY, hi5 = -INFINITY;
    float white = 0.0f, crease = 0.0f;
    for (long dy = -2; dy <= 2; dy++) {
        long yy = clamp(y + dy, 0L, H - 1);
        for (long dx = -2; dx <= 2; dx++) {
            long xx = clamp(x + dx, 0L, W - 1), j = yy * W + xx;
            int inner = dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1;
            float g = grey_at(image, j);
            lo5 = fmin(lo5, g);
            hi5 = fmax(hi5, g);
#if RGB && HAS_COLOUR
            float top = fmax(image[3 * j], fmax(image[3 * j + 1], image[3 * j + 2]));
            float bottom = fmin(image[3 * j], fmin(image[3 * j + 1], image[3 * j + 2]));
            white = fmax(white, bottom / fmax(top, 1e-3f));
#endif
            if (inner) {
                near |= support[j];
                lo3 = fmin(lo3, g);
                hi3 = fmax(hi3, g);
#if HAS_STEREO
                crease = fmax(crease, crease_at(disparity, xx, yy, W, H));
#endif
            }
        }
    }
    in[F_STEREO_LINE] = (near & BIT_STEREO) != 0;
    in[F_MOTION_LINE] = (near & BIT_MOTION) != 0;
    in[F_COLOUR_LINE] = (near & BIT_COLOUR) != 0;
    in[F_TEXTURE_LINE] = (near & BIT_TEXTURE) != 0;
    in[F_BRIGHTNESS_EDGE] = (support[i] & BIT_BRIGHTNESS) != 0;
#if HAS_STEREO
    in[F_DISPARITY_JUMP_3] = CLIPPED(window_range(disparity, 1, 0, x, y, 1, W, H), 4.0f);
    in[F_DISPARITY_JUMP_7] = CLIPPED(window_range(disparity, 1, 0, x, y, 3, W, H), 4.0f);
    in[F_DISPARITY_CREASE] = CLIPPED(crease, 2.0f);
#endif
#if HAS_MOTION
    in[F_FLOW_JUMP_3] = CLIPPED(fmax(window_range(flow, 2, 0, x, y, 1, W, H), window_range(flow, 2, 1, x, y, 1, W, H)), 4.0f);
    in[F_FLOW_JUMP_7] = CLIPPED(fmax(window_range(flow, 2, 0, x, y, 3, W, H), window_range(flow, 2, 1, x, y, 3, W, H)), 4.0f);
#endif
    in[F_LOG_BRIGHTNESS_STEP_3] = CLIPPED(log(fmax(hi3, 1e-3f)) - log(fmax(lo3, 1e-3f)), 1.5f);
    in[F_LOG_BRIGHTNESS_STEP_5] = CLIPPED(log(fmax(hi5, 1e-3f)) - log(fmax(lo5, 1e-3f)), 1.5f);
#if HAS_COLOUR
    in[F_HUE_STEP_3] = CLIPPED(window_range(hue, 1, 0, x, y, 1, W, H), 0.3f);
#endif
    in[F_WHITENESS_5] = white;
    in[F_BRIGHTNESS_5] = fmax(hi5, 0.0f);  /* as the running maximum from 0 it was: a dark window's is 0 */

#if CLASSIFY
    uchar label = 0;
    float best = -INFINITY, score[NC];
    for (int c = 0; c < NC; c++) {
        float s = weights[c];  /* row 0: the bias */
        for (int k = 0; k < NF; k++) s += weights[(k + 1) * NC + c] * in[k];
        score[c] = s;
        if (s > best) { best = s; label = codes[c]; }
    }
    labels[i] = label;
    /* The support for "some discontinuity": 1 - the softmax's share of class 0, NONE (the fit's model).
     * With the image's probability of boundary, which already weighs brightness, colour and texture,
     * the classifier adds what the image cannot see: the lines of stereo and motion. */
    float total = 0.0f;
    for (int c = 0; c < NC; c++) total += exp(score[c] - best);
    float some = 1.0f - exp(score[0] - best) / total;
#if HAS_PROBABILITY
    strength[i] = (support[i] & (BIT_STEREO | BIT_MOTION)) ? fmax(seen, some) : seen;
#else
    strength[i] = some;
#endif
#else
    for (int k = 0; k < NF; k++) features[(size_t)k * W * H + i] = in[k];
#endif
}
