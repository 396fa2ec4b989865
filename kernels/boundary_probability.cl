/* boundary_probability.cl: the probability of a boundary at every pixel from brightness, colour and
 * texture gradients at several scales (vmcl/early/boundary_probability.py). One work-item per pixel
 * over a (W, H) grid; ids past the field idle. Borders clamp.
 *
 *   lab              CIE L*a*b* (D65, sRGB companding) of an RGB or grey image, each divided by 100
 *   bank             the filter-bank responses (first and second directional derivatives and the
 *                    Laplacian of the lightness at two scales), compressed by their norm
 *   nearest          each pixel's texton: the nearest of the centres to its responses
 *   histogram_rows   a row pass of the Gaussian over the textons' indicator planes: NT planes out, at every
 *                    step-th column (a wide Gaussian's output is smooth enough to be sampled sparsely)
 *   planes_rows      a row pass of the Gaussian over a stack of float planes
 *   planes_cols      the column pass over a stack of float planes, at every step-th row
 *   planes_upsample  a stack sampled at every step_x-th column and step_y-th row, interpolated bilinearly to
 *                    every pixel
 *   components       one scale's gradient components: (gx, gy) of L, a and b, and the texture tensor
 *                    (sum over textons of gx^2, gx gy, gy^2 of the smoothed indicator planes), which
 *                    the host then integrates (smooths) at the texture's scale; nt 0: no tensor (the
 *                    scale's histograms are sampled, and sampled_tensor forms it)
 *   sampled_tensor   the texture tensor on the grid of histograms sampled at every step-th pixel
 *   strongest        each gradient's largest value over all orientations (the surround's source)
 *   oriented         the features at each of NORIENT orientations (for fitting)
 *   probability      the logistic classifier at each orientation; the largest wins
 *   thin             non-maximum suppression across the winning orientation
 *
 * Defines: IN_T, CHANNELS and LINEAR_TABLE (lab); NBANK (bank, nearest); NT (histogram_rows, components,
 * sampled_tensor);
 * NSCALES, NORIENT, NFEAT, SURROUND_FLOOR (strongest, oriented, probability, thin); VEC, the pixels of a row
 * a work-item takes where a kernel takes several (the host builds every kernel with the Machine's vector
 * width but oriented, which exists for VEC 1 only: it is for fitting).
 */
#include "vmcl.h"
#include "sampling.h"

#define AT(f, xx, yy) ((f)[(yy) * W + (xx)])
#define PLANE(f, p, xx, yy) ((f)[IDX3((xx), (yy), (p), W, H)])

/* Kernels that take VEC pixels of a row per work-item (VT lanes; VEC is 1 on GPUs) read a plane's chunk
 * contiguously inside the row; a row's last, partial chunk reads its last pixel again in the lanes past
 * the end, and stores only the lanes inside. */
#define T float
inline VT chunk_at(__global const float *plane, long x0, long y, long W)
{
    __global const float *row = plane + y * W;
    if (x0 + VEC <= W) return VLOAD(row + x0);
    float t[VEC];
    for (int i = 0; i < VEC; i++) t[i] = row[min(x0 + i, W - 1)];
    return VLOAD(t);
}

/* v's lanes inside the row into plane p of out. */
inline void store_chunk(__global float *out, int p, long x0, long y, long W, long H, VT v)
{
    __global float *row = out + ((size_t)p * H + y) * W;
    if (x0 + VEC <= W) {
        VSTORE(v, row + x0);
        return;
    }
    float t[VEC];
    VSTORE(v, t);
    for (int i = 0; x0 + i < W; i++) row[x0 + i] = t[i];
}

/* The lanes of v inside the row, as bytes. */
inline void store_bytes(__global uchar *row, long x0, long W, VIT v)
{
    int t[VEC];
#if VEC == 1
    t[0] = v;
#else
    VCAT(vstore, VEC)(v, 0, t);
#endif
    for (int i = 0; i < VEC && x0 + i < W; i++) row[x0 + i] = (uchar)t[i];
}

#ifdef IN_T
inline VT srgb_linear(VT c)
{
    return select(exp2(2.4f * log2((c + 0.055f) / 1.055f)), c / 12.92f, c <= 0.04045f);
}

inline VT lab_f(VT t)
{
    return select(t * 7.787037f + 16.0f / 116.0f, exp2(log2(t) * (1.0f / 3.0f)), t > 0.008856452f);
}

/* Channel c of the chunk's pixels (the last pixel again past the row's end), linear: 8-bit input through
 * its 256 linear values, tabulated by the host (the power law is the kernel's dearest step). */
inline VT linear_chunk(__global const IN_T *in, __constant float *linear, float scale, int c, long x0, long y,
                       long W)
{
    float t[VEC];
    for (int i = 0; i < VEC; i++) {
        IN_T v = in[((size_t)y * W + min(x0 + i, W - 1)) * CHANNELS + c];
#if LINEAR_TABLE
        t[i] = linear[(int)v];
#else
        t[i] = clamp((float)v / scale, 0.0f, 1.0f);
#endif
    }
#if LINEAR_TABLE
    return VLOAD(t);
#else
    return srgb_linear(VLOAD(t));
#endif
}

/* out: the (3, H, W) planes L, a, b. scale: the input's full scale (255 for uint8, 65535 for uint16,
 * 1 for float). linear: with LINEAR_TABLE, the linear value of each 8-bit level. VEC pixels of a row per
 * work-item. */
__kernel void lab(__global const IN_T *in, __global float *out, __constant float *linear, float scale, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
#if CHANNELS == 3
    VT r = linear_chunk(in, linear, scale, 0, x0, y, W), g = linear_chunk(in, linear, scale, 1, x0, y, W);
    VT b = linear_chunk(in, linear, scale, 2, x0, y, W);
    VT fx = lab_f((0.412453f * r + 0.357580f * g + 0.180423f * b) / 0.950456f);
    VT fy = lab_f(0.212671f * r + 0.715160f * g + 0.072169f * b);
    VT fz = lab_f((0.019334f * r + 0.119193f * g + 0.950227f * b) / 1.088754f);
    store_chunk(out, 0, x0, y, W, H, (116.0f * fy - 16.0f) / 100.0f);
    store_chunk(out, 1, x0, y, W, H, 5.0f * (fx - fy));
    store_chunk(out, 2, x0, y, W, H, 2.0f * (fy - fz));
#else
    /* Grey: the lightness of a neutral colour of that luminance; no chroma. */
    store_chunk(out, 0, x0, y, W, H, (116.0f * lab_f(linear_chunk(in, linear, scale, 0, x0, y, W)) - 16.0f) / 100.0f);
    store_chunk(out, 1, x0, y, W, H, (VT)0.0f);
    store_chunk(out, 2, x0, y, W, H, (VT)0.0f);
#endif
}
#endif

#ifdef NBANK
/* The bank at one scale for VEC pixels of a row: the first and second derivatives along 0, 45, 90 and 135
 * degrees, then the Laplacian, each scale-normalised (sigma for first, sigma^2 for second derivatives).
 * Neighbours past the field's borders are the border's own (clamped). */
static void bank_chunk(__global const float *s, float sigma, long x0, long y, long W, long H, VT *out)
{
    __global const float *row = s + y * W, *up = s + max(y - 1, 0L) * W, *down = s + min(y + 1, H - 1) * W;
    VT c = clamped_chunk(row, x0, W), left = clamped_chunk(row, x0 - 1, W), right = clamped_chunk(row, x0 + 1, W);
    VT above = clamped_chunk(up, x0, W), below = clamped_chunk(down, x0, W);
    VT gx = 0.5f * (right - left), gy = 0.5f * (below - above);
    VT gxx = right - 2.0f * c + left, gyy = below - 2.0f * c + above;
    VT gxy = 0.25f * (clamped_chunk(down, x0 + 1, W) - clamped_chunk(down, x0 - 1, W) - clamped_chunk(up, x0 + 1, W)
                      + clamped_chunk(up, x0 - 1, W));
    const float cosines[4] = {1.0f, M_SQRT1_2_F, 0.0f, -M_SQRT1_2_F}, sines[4] = {0.0f, M_SQRT1_2_F, 1.0f, M_SQRT1_2_F};
    float s2 = sigma * sigma;
    for (int k = 0; k < 4; k++) {
        float co = cosines[k], si = sines[k];
        out[2 * k] = sigma * (gx * co + gy * si);
        out[2 * k + 1] = s2 * (gxx * co * co + 2.0f * gxy * co * si + gyy * si * si);
    }
    out[8] = s2 * (gxx + gyy);
}

/* Responses are compressed by their norm n to log(1 + n / 0.03) (Malik et al. 2001), so the textons
 * describe the shape of the local pattern more than its contrast. out: (H, W, NBANK), VEC pixels of a row
 * per work-item. */
__kernel void bank(__global const float *fine, __global const float *coarse, __global float *out,
                   float fine_sigma, float coarse_sigma, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    VT r[NBANK];
    bank_chunk(fine, fine_sigma, x0, y, W, H, r);
    bank_chunk(coarse, coarse_sigma, x0, y, W, H, r + NBANK / 2);
    VT n = (VT)0.0f;
    for (int j = 0; j < NBANK; j++) n += r[j] * r[j];
    n = sqrt(n);
    VT gain = select((VT)0.0f, log1p(n / 0.03f) / n, n > 0.0f);
    __global float *dst = out + ((size_t)y * W + x0) * NBANK;
    long lanes = min((long)VEC, W - x0);
    for (int j = 0; j < NBANK; j++) {
        float t[VEC];
        VSTORE(gain * r[j], t);
        for (long i = 0; i < lanes; i++) dst[i * NBANK + j] = t[i];
    }
}

/* The nearest of the nt texton centres (nt x NBANK) in the compressed response space, VEC pixels of a row
 * per work-item: their responses are gathered once (stride NBANK), then every centre is a vector step. */
__kernel void nearest(__global const float *responses, __global const float *centres, __global uchar *label,
                      int nt, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    VT r[NBANK];
    for (int j = 0; j < NBANK; j++) {
        float t[VEC];
        for (int i = 0; i < VEC; i++) t[i] = responses[((size_t)y * W + min(x0 + i, W - 1)) * NBANK + j];
        r[j] = VLOAD(t);
    }
    VIT best = (VIT)0;
    VT best_d = (VT)INFINITY;
    for (int k = 0; k < nt; k++) {
        VT d = (VT)0.0f;
        for (int j = 0; j < NBANK; j++) {
            VT e = r[j] - centres[k * NBANK + j];
            d += e * e;
        }
        VIT closer = d < best_d;
        best_d = select(best_d, d, closer);
        best = select(best, (VIT)k, closer);
    }
    store_bytes(label + y * W, x0, W, best);
}
#endif


#ifdef NT
/* Each sample's share of each texton in the Gaussian row window: one pass over the taps, the weight
 * added to the texton met (a histogram), not NT passes. Work-item (xc, y) is pixel (xc step, y), written
 * at (xc, y) of Wc-wide planes; columns past the image read its last one. */
__kernel void histogram_rows(__global const uchar *label, __global float *out, __global const float *taps, int radius,
                             int step, long Wc, long W, long H)
{
    long xc = get_global_id(0), y = get_global_id(1);
    if (xc >= Wc || y >= H) return;
    long x = xc * step;
    float acc[NT];
    for (int k = 0; k < NT; k++) acc[k] = 0.0f;
    for (int t = -radius; t <= radius; t++)
        acc[AT(label, clamp(x + t, 0L, W - 1), y)] += taps[t + radius];
    for (int k = 0; k < NT; k++) out[IDX3(xc, y, k, Wc, H)] = acc[k];
}
#endif

/* Plane p of a (P, Hc, Wc) stack sampled at every step_x-th column and step_y-th row, bilinearly at each
 * pixel of plane first + p of (., H, W). */
__kernel void planes_upsample(__global const float *in, __global float *out, int step_x, int step_y, long first,
                              long Wc, long Hc, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= W || y >= H) return;
    out[IDX3(x, y, first + p, W, H)] = bilinear_clamped(in + (size_t)p * Hc * Wc, (float)x / (float)step_x,
                                                        (float)y / (float)step_y, Wc, Hc);
}

#ifdef VEC
/* The Gaussian's row and column passes over a (P, H, W) stack into planes first .. first + P - 1 of
 * out, work-item (k, y, p) standing for the VEC pixels [k VEC, (k + 1) VEC) of row y of plane p: one vector
 * step per tap (PoCL then runs the CPU's SIMD lanes over contiguous loads), near a row's ends through
 * clamped_chunk (vmcl.h); the column pass clamps its rows. */
__kernel void planes_rows(__global const float *in, __global float *out, __global const float *taps, int r,
                          long first, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1), p = get_global_id(2);
    if (x0 >= W || y >= H) return;
    __global const float *row = in + (p * H + y) * W;
    VT acc = (VT)0.0f;
    if (x0 >= r && x0 + VEC + r <= W) {
        for (int k = -r; k <= r; k++) acc += taps[k + r] * VLOAD(row + x0 + k);
    } else {
        /* Near an end, still in vector steps: a pixel-by-pixel loop there would take 6 of a 256-wide
         * row's 16 chunks at the surround's radius (40). */
        for (int k = -r; k <= r; k++) acc += taps[k + r] * clamped_chunk(row, x0 + k, W);
    }
    store_chunk(out, first + p, x0, y, W, H, acc);
}

/* planes_cols: output row yc of (P, Hout, W) is input row yc step (rows past the image read its last). */
__kernel void planes_cols(__global const float *in, __global float *out, __global const float *taps, int r,
                          long first, int step, long Hout, long W, long H)
{
    long x0 = get_global_id(0) * VEC, yc = get_global_id(1), p = get_global_id(2);
    if (x0 >= W || yc >= Hout) return;
    long y = yc * step;
    __global const float *plane = in + p * H * W;
    out += first * Hout * W;
    if (x0 + VEC <= W) {
        VT acc = (VT)0.0f;
        for (int k = -r; k <= r; k++) acc += taps[k + r] * VLOAD(plane + clamp(y + k, 0L, H - 1) * W + x0);
        VSTORE(acc, out + (p * Hout + yc) * W + x0);
        return;
    }
    for (long x = x0; x < W; x++) {
        float acc = 0.0f;
        for (int k = -r; k <= r; k++) acc += taps[k + r] * plane[clamp(y + k, 0L, H - 1) * W + x];
        out[(p * Hout + yc) * W + x] = acc;
    }
}
#endif

#ifdef NT
/* Centred differences, scale-normalised: sigma times the gradient of a field smoothed at sigma gives a
 * step the same peak at every scale. lab: 3 planes smoothed at sigma; hist: NT planes smoothed at
 * texture_sigma. comp: this scale's 6 planes from plane 6 k: gx, gy of L, a and b; tensor: the 3 planes
 * txx, txy, tyy of the texture tensor before its integration (the host smooths them). VEC pixels of a
 * row per work-item: contiguous loads inside the row, pixel by pixel in the chunks at its ends (the same
 * arithmetic, so the two agree to the bit). */
__kernel void components(__global const float *lab, __global const float *hist, __global float *comp,
                         __global float *tensor, float sigma, float texture_sigma, int nt, int k, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    long ym = max(y - 1, 0L), yp = min(y + 1, H - 1);
    if (x0 >= 1 && x0 + VEC + 1 <= W) {
        for (int p = 0; p < 3; p++) {
            VT gx = 0.5f * sigma * (VLOAD(&PLANE(lab, p, x0 + 1, y)) - VLOAD(&PLANE(lab, p, x0 - 1, y)));
            VT gy = 0.5f * sigma * (VLOAD(&PLANE(lab, p, x0, yp)) - VLOAD(&PLANE(lab, p, x0, ym)));
            VSTORE(gx, &PLANE(comp, 6 * k + 2 * p, x0, y));
            VSTORE(gy, &PLANE(comp, 6 * k + 2 * p + 1, x0, y));
        }
        VT txx = (VT)0.0f, txy = (VT)0.0f, tyy = (VT)0.0f;
        for (int j = 0; j < nt; j++) {
            VT gx = 0.5f * texture_sigma * (VLOAD(&PLANE(hist, j, x0 + 1, y)) - VLOAD(&PLANE(hist, j, x0 - 1, y)));
            VT gy = 0.5f * texture_sigma * (VLOAD(&PLANE(hist, j, x0, yp)) - VLOAD(&PLANE(hist, j, x0, ym)));
            txx += gx * gx; txy += gx * gy; tyy += gy * gy;
        }
        if (nt) {
            VSTORE(txx, &PLANE(tensor, 0, x0, y));
            VSTORE(txy, &PLANE(tensor, 1, x0, y));
            VSTORE(tyy, &PLANE(tensor, 2, x0, y));
        }
        return;
    }
    for (long x = x0; x < min(x0 + VEC, W); x++) {
        long xm = max(x - 1, 0L), xp = min(x + 1, W - 1);
        for (int p = 0; p < 3; p++) {
            PLANE(comp, 6 * k + 2 * p, x, y) = 0.5f * sigma * (PLANE(lab, p, xp, y) - PLANE(lab, p, xm, y));
            PLANE(comp, 6 * k + 2 * p + 1, x, y) = 0.5f * sigma * (PLANE(lab, p, x, yp) - PLANE(lab, p, x, ym));
        }
        float txx = 0.0f, txy = 0.0f, tyy = 0.0f;
        for (int j = 0; j < nt; j++) {
            float gx = 0.5f * texture_sigma * (PLANE(hist, j, xp, y) - PLANE(hist, j, xm, y));
            float gy = 0.5f * texture_sigma * (PLANE(hist, j, x, yp) - PLANE(hist, j, x, ym));
            txx += gx * gx; txy += gx * gy; tyy += gy * gy;
        }
        if (nt) {
            PLANE(tensor, 0, x, y) = txx;
            PLANE(tensor, 1, x, y) = txy;
            PLANE(tensor, 2, x, y) = tyy;
        }
    }
}

/* The texture tensor of histograms sampled at every step-th pixel ((NT, H, W) in, (3, H, W) out, W x H that
 * grid's size), on that grid: scale is the texture's sigma over the step (the derivative per pixel of the
 * image). The derivatives are the five-point stencil's: on a grid spaced one sigma apart, centred differences
 * fall some 16% short on a wave of angular frequency 1 / sigma, the five-point stencil 3%. */
__kernel void sampled_tensor(__global const float *hist, __global float *tensor, float scale, int nt, long W,
                             long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long x1 = max(x - 1, 0L), x2 = max(x - 2, 0L), x3 = min(x + 1, W - 1), x4 = min(x + 2, W - 1);
    long y1 = max(y - 1, 0L), y2 = max(y - 2, 0L), y3 = min(y + 1, H - 1), y4 = min(y + 2, H - 1);
    float txx = 0.0f, txy = 0.0f, tyy = 0.0f, c = scale / 12.0f;
    for (int j = 0; j < nt; j++) {
        float gx = c * (8.0f * (PLANE(hist, j, x3, y) - PLANE(hist, j, x1, y)) - PLANE(hist, j, x4, y)
                        + PLANE(hist, j, x2, y));
        float gy = c * (8.0f * (PLANE(hist, j, x, y3) - PLANE(hist, j, x, y1)) - PLANE(hist, j, x, y4)
                        + PLANE(hist, j, x, y2));
        txx += gx * gx; txy += gx * gy; tyy += gy * gy;
    }
    PLANE(tensor, 0, x, y) = txx;
    PLANE(tensor, 1, x, y) = txy;
    PLANE(tensor, 2, x, y) = tyy;
}
#endif

#ifdef NORIENT
/* The pixels' derivative components and texture tensors, read from global memory once for all the
 * orientations: comp holds NSCALES x 6 planes (d/dx, d/dy of L, a and b), tensors NSCALES x 3. */
static void pixel_at(__global const float *comp, __global const float *tensors, long x0, long y, long W, long H,
                     VT *d, VT *t)
{
    for (int j = 0; j < 6 * NSCALES; j++) d[j] = chunk_at(comp + j * H * W, x0, y, W);
    for (int j = 0; j < 3 * NSCALES; j++) t[j] = chunk_at(tensors + j * H * W, x0, y, W);
}

/* The gradients across orientation theta (the boundary's normal at theta, (c, s) = (cos, sin) theta), 4 per
 * scale: |d/dn| of L, a and b, and the norm of the texton histograms' derivative (from the integrated
 * texture tensor). */
static void gradients_at(const VT *d, const VT *t3, float c, float s, VT *g)
{
    for (int sc = 0; sc < NSCALES; sc++) {
        for (int p = 0; p < 3; p++)
            g[4 * sc + p] = fabs(c * d[6 * sc + 2 * p] + s * d[6 * sc + 2 * p + 1]);
        VT q = c * c * t3[3 * sc] + 2.0f * c * s * t3[3 * sc + 1] + s * s * t3[3 * sc + 2];
        g[4 * sc + 3] = sqrt(max(q, 0.0f));
    }
}

/* The classifier's inputs: the gradients g, their square roots (the classifier is linear in both,
 * which lets it bend its response to contrast), and the square roots of g over the surround's mean
 * gradient (surround: 4 NSCALES planes) plus SURROUND_FLOOR: a gradient among many like it (a texture's
 * inner edges) counts less than the same gradient alone, the surround suppression of contour detectors. */
static void features_at(const VT *d, const VT *t3, const VT *inv_surround, float c, float s, VT *f)
{
    const int n = 4 * NSCALES;
    gradients_at(d, t3, c, s, f);
    for (int j = 0; j < n; j++) {
        f[n + j] = sqrt(f[j]);
        f[2 * n + j] = f[n + j] * inv_surround[j];
    }
}

/* 1 / sqrt(SURROUND_FLOOR + surround) of each gradient at the pixels: the same at every orientation. */
static void inverse_surround(__global const float *surround, long x0, long y, long W, long H, VT *inv)
{
    for (int j = 0; j < 4 * NSCALES; j++) inv[j] = rsqrt(SURROUND_FLOOR + chunk_at(surround + j * H * W, x0, y, W));
}

/* The length of (a, b): the gradients here are small (images in [0, 1]), so no rescaling against
 * overflow is needed, which makes hypot() several times dearer on CPUs. */
inline VT norm2(VT a, VT b)
{
    return sqrt(a * a + b * b);
}

/* Each gradient's largest value over all orientations, (4 NSCALES, H, W): what the surround averages.
 * For L, a and b the gradient's norm; for the texture the square root of its tensor's larger eigenvalue.
 * VEC pixels of a row per work-item. */
__kernel void strongest(__global const float *comp, __global const float *tensors, __global float *out, long W,
                        long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    VT d[6 * NSCALES], t3[3 * NSCALES];
    pixel_at(comp, tensors, x0, y, W, H, d, t3);
    for (int sc = 0; sc < NSCALES; sc++) {
        for (int p = 0; p < 3; p++)
            store_chunk(out, 4 * sc + p, x0, y, W, H, norm2(d[6 * sc + 2 * p], d[6 * sc + 2 * p + 1]));
        VT a = t3[3 * sc], b = t3[3 * sc + 1], c = t3[3 * sc + 2];
        VT largest = 0.5f * (a + c) + sqrt(0.25f * (a - c) * (a - c) + b * b);
        store_chunk(out, 4 * sc + 3, x0, y, W, H, sqrt(max(largest, 0.0f)));
    }
}

#if VEC == 1
/* out: (NORIENT, H, W, NFEAT), a pixel per work-item (only built with VEC 1: it is for fitting). directions: (cos, sin) of each
 * orientation's angle, o pi / NORIENT (a table: the trigonometric functions were a large share of the
 * classifier's time). */
__kernel void oriented(__global const float *comp, __global const float *tensors, __global const float *surround,
                       __constant float *directions, __global float *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    VT f[NFEAT], inv[4 * NSCALES], d[6 * NSCALES], t3[3 * NSCALES];
    inverse_surround(surround, x, y, W, H, inv);
    pixel_at(comp, tensors, x, y, W, H, d, t3);
    for (int o = 0; o < NORIENT; o++) {
        features_at(d, t3, inv, directions[2 * o], directions[2 * o + 1], f);
        __global float *dst = out + (((size_t)o * H + y) * W + x) * NFEAT;
        for (int j = 0; j < NFEAT; j++) dst[j] = f[j];
    }
}
#endif

/* weights: bias, then NFEAT weights. directions: as for oriented. theta: the index of the winning
 * orientation. VEC pixels of a row per work-item. */
__kernel void probability(__global const float *comp, __global const float *tensors, __global const float *surround,
                          __constant float *directions, __constant float *weights, __global float *p,
                          __global uchar *theta, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    VT f[NFEAT], inv[4 * NSCALES], d[6 * NSCALES], t3[3 * NSCALES];
    inverse_surround(surround, x0, y, W, H, inv);
    pixel_at(comp, tensors, x0, y, W, H, d, t3);
    VT best = (VT)(-INFINITY);
    VIT best_o = (VIT)0;
    for (int o = 0; o < NORIENT; o++) {
        features_at(d, t3, inv, directions[2 * o], directions[2 * o + 1], f);
        VT z = (VT)weights[0];
        for (int j = 0; j < NFEAT; j++) z += weights[1 + j] * f[j];
        VIT better = z > best;
        best = select(best, z, better);
        best_o = select(best_o, (VIT)o, better);
    }
    store_chunk(p, 0, x0, y, W, H, 1.0f / (1.0f + exp(-best)));
    store_bytes(theta + y * W, x0, W, best_o);
}

/* A pixel keeps its probability when no point one pixel away along the normal has more, and the point on the
 * normal's side has less: of a plateau along the normal (a flat image's floor, a ridge two pixels wide) one
 * edge survives, not all of it. */
__kernel void thin(__global const float *p, __global const uchar *theta, __constant float *directions,
                   __global float *out, __global float *angle, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    int o = AT(theta, x, y);
    float c = directions[2 * o], s = directions[2 * o + 1];
    float v = AT(p, x, y);
    float a = bilinear_clamped(p, x + c, y + s, W, H), b = bilinear_clamped(p, x - c, y - s, W, H);
    AT(out, x, y) = (v > a && v >= b) ? v : 0.0f;
    // The winning normal's angle in radians, written here so that no separate conversion is built.
    AT(angle, x, y) = (float)o * (M_PI_F / NORIENT);
}
#endif
