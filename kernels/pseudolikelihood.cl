/* pseudolikelihood.cl: Besag's pseudolikelihood of the line-process MRF, seed section "Learning and
 * parameter estimation" (vmcl/learn/pseudolikelihood.py drives it and documents the model in full).
 *
 * The energy of mrf.cl divided by the temperature is linear in its natural parameters
 *   theta = (alpha, coupling, line, edge_gain, end, continuation, turn, junction, crossing, parallel) / T
 * (coupling: 1 for the smooth kind's membrane, kappa for the constant kind's Potts cost; the prior's
 * entries times beta). Each site's conditional given every other site is then an exponential family in
 * theta, and the negative log pseudolikelihood is a sum over sites of convex terms. The feature kernels
 * write each site's options and features once (they do not depend on theta); the *_terms kernels sum,
 * for one theta, each chunk of CHUNK sites' negative log conditional, its gradient and its Hessian (upper
 * triangle, row by row) into one row of partial sums, which the host adds in float64. Every site is
 * scored at once: the conditionals are read from the fixed configuration, so no colouring is needed.
 *
 * Line fields arrive padded to H x W as in mrf.cl: lh[y, x] between (y, x) and (y, x + 1) (last column
 * 0), lv[y, x] between (y, x) and (y + 1, x) (last row 0); vertex (y, x) has arms up = lh[y, x] (bit 0),
 * down = lh[y + 1, x] (bit 1), left = lv[y, x] (bit 2), right = lv[y, x + 1] (bit 3).
 *
 * Defines: NCOMP (field components), KIND (0 smooth, 1 constant), NLEVELS (constant kind's levels) for
 * the feature kernels; NOPT, K (options per site, features per option) for softmax_terms.
 */
#include "vmcl.h"

/* Every kernel is built with every define; those a launch does not use take these values. */
#ifndef NCOMP
#define NCOMP 1
#endif
#ifndef KIND
#define KIND 0
#endif
#ifndef NLEVELS
#define NLEVELS 2
#endif
#ifndef NOPT
#define NOPT 2
#endif
#ifndef K
#define K 1
#endif
#ifndef CHUNK
#define CHUNK 64
#endif
#include "bond.h"

/* The line site's features, in the order of theta[1:] (vmcl/learn/pseudolikelihood.py LINE_PARAMS). */
#define LINE_K 9
#define F_COUPLING 0
#define F_LINE 1
#define F_EDGE 2
#define F_END 3
#define F_PARALLEL 8

/* The prior's class of a vertex with these arms: -1 empty, else the feature index of end, continuation,
 * turn, junction or crossing. */
inline int vertex_class(int arms)
{
    int count = popcount(arms);
    if (count == 0) return -1;
    if (count == 2) return (arms == 3 || arms == 12) ? F_END + 1 : F_END + 2;
    return count == 1 ? F_END : F_END + count;
}

/* A vertex's features change when the arm at `bit` turns on, the other arms being `others`. */
inline void vertex_change(float *x, int others, int bit)
{
    int before = vertex_class(others), after = vertex_class(others | (1 << bit));
    if (before >= 0) x[before] -= 1.0f;
    x[after] += 1.0f;
}

/* One line site per work-item, (x, y, type): two options (off: features 0; on: the change of every
 * clique that holds the site, whose dot product with theta is dE / T) and the observed state, or -1
 * where the site does not exist, either pixel lies outside `valid`, or the model forbids a line there
 * (`usable`, per site as `observed` is laid out: a line far from every edge under require_edge). */
__kernel void line_features(__global const float *f, __global const uchar *lh, __global const uchar *lv,
                            __global const uchar *edges, int has_edges, __global const uchar *valid,
                            __global const uchar *usable, __global float *features, __global int *observed,
                            long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    int type = get_global_id(2);
    if (x >= W || y >= H) return;
    long i = y * W + x, site = type * W * H + i, j = type == 0 ? i + 1 : i + W;
    int exists = type == 0 ? x < W - 1 : y < H - 1;
    float on[LINE_K];
    for (int k = 0; k < LINE_K; ++k) on[k] = 0.0f;
    __global float *out = features + site * 2 * LINE_K;
    if (!exists || !valid[i] || !valid[j] || !usable[site]) {
        observed[site] = -1;
        for (int k = 0; k < 2 * LINE_K; ++k) out[k] = 0.0f;
        return;
    }
    on[F_COUPLING] = -bond_cost(f, i, j, 1.0f);
    on[F_LINE] = 1.0f;
    on[F_EDGE] = has_edges && (edges[i] || edges[j]) ? -1.0f : 0.0f;
    if (type == 0) {
        if (y > 0) vertex_change(on, (lh[i - W] != 0) | (lv[i - W] != 0) << 2 | (lv[i - W + 1] != 0) << 3, 1);
        if (y < H - 1) vertex_change(on, (lh[i + W] != 0) << 1 | (lv[i] != 0) << 2 | (lv[i + 1] != 0) << 3, 0);
        on[F_PARALLEL] = (x > 0 ? (float)(lh[i - 1] != 0) : 0.0f) + (x + 1 < W - 1 ? (float)(lh[i + 1] != 0) : 0.0f);
    } else {
        if (x > 0) vertex_change(on, (lh[i - 1] != 0) | (lh[i + W - 1] != 0) << 1 | (lv[i - 1] != 0) << 2, 3);
        if (x < W - 1) vertex_change(on, (lh[i] != 0) | (lh[i + W] != 0) << 1 | (lv[i + 1] != 0) << 3, 2);
        on[F_PARALLEL] = (y > 0 ? (float)(lv[i - W] != 0) : 0.0f) + (y + 1 < H - 1 ? (float)(lv[i + W] != 0) : 0.0f);
    }
    for (int k = 0; k < LINE_K; ++k) {
        out[k] = 0.0f;
        out[LINE_K + k] = on[k];
    }
    observed[site] = (type == 0 ? lh : lv)[i] != 0;
}

/* The four neighbours of pixel i and whether its bond to each holds (no line, inside the image). */
inline void bonds(__global const uchar *lh, __global const uchar *lv, long x, long y, long i, long W, long H,
                  long *nb, int *keep)
{
    nb[0] = i - 1; keep[0] = x > 0 && !lh[i - 1];
    nb[1] = i + 1; keep[1] = x < W - 1 && !lh[i];
    nb[2] = i - W; keep[2] = y > 0 && !lv[i - W];
    nb[3] = i + W; keep[3] = y < H - 1 && !lv[i];
}

/* A pixel's conditional is scored where it and every neighbour it is bonded to lie inside `valid`. */
inline int scored(__global const uchar *valid, long i, const long *nb, const int *keep)
{
    int ok = valid[i] != 0;
    for (int m = 0; m < 4; ++m) ok &= !keep[m] || valid[nb[m]];
    return ok;
}

/* The constant kind's pixel sites: one option per level, features (gamma (level - g)^2, the count of
 * bonded neighbours at another level), the observed level's index (-1: not a level, or not scored). */
__kernel void potts_features(__global const float *f, __global const float *g, __global const float *gamma,
                             __global const uchar *lh, __global const uchar *lv, __constant float *levels,
                             __global const uchar *valid, __global float *features, __global int *observed,
                             long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x, nb[4];
    int keep[4];
    bonds(lh, lv, x, y, i, W, H, nb, keep);
    int found = -1;
    for (int k = 0; k < NLEVELS; ++k) {
        float d = gamma[i] > 0.0f ? levels[k] - g[i] : 0.0f, differ = 0.0f;
        for (int m = 0; m < 4; ++m) differ += keep[m] && f[nb[m]] != levels[k] ? 1.0f : 0.0f;
        features[(i * NLEVELS + k) * 2] = gamma[i] * d * d;
        features[(i * NLEVELS + k) * 2 + 1] = differ;
        if (f[i] == levels[k]) found = k;
    }
    observed[i] = scored(valid, i, nb, keep) ? found : -1;
}

/* Sums over CHUNK sites per work-item of a softmax conditional: option o of a site has energy
 * theta . phi_o, probability p_o = exp(-E_o) / sum exp(-E); the site adds -log p_obs, its gradient
 * phi_obs - E_p[phi] and its Hessian Cov_p(phi). Sites with observed < 0 add nothing. Row layout:
 * [value, gradient (K), Hessian upper triangle (K (K + 1) / 2)]. */
#define ROW (1 + K + K * (K + 1) / 2)
__kernel void softmax_terms(__global const float *features, __global const int *observed,
                            __constant float *theta, long sites, __global float *out)
{
    long item = get_global_id(0);
    long first = item * CHUNK;
    if (first >= sites) return;
    float acc[ROW];
    for (int r = 0; r < ROW; ++r) acc[r] = 0.0f;
    for (long s = first; s < min(first + CHUNK, sites); ++s) {
        int obs = observed[s];
        if (obs < 0) continue;
        __global const float *phi = features + s * NOPT * K;
        float energy[NOPT], lowest = INFINITY;
        for (int o = 0; o < NOPT; ++o) {
            float e = 0.0f;
            for (int k = 0; k < K; ++k) e += theta[k] * phi[o * K + k];
            energy[o] = e;
            lowest = fmin(lowest, e);
        }
        float total = 0.0f;
        for (int o = 0; o < NOPT; ++o) {
            energy[o] = exp(lowest - energy[o]);
            total += energy[o];
        }
        float mean[K];
        for (int k = 0; k < K; ++k) mean[k] = 0.0f;
        for (int o = 0; o < NOPT; ++o)
            for (int k = 0; k < K; ++k) mean[k] += energy[o] / total * phi[o * K + k];
        float e_obs = 0.0f;
        for (int k = 0; k < K; ++k) e_obs += theta[k] * phi[obs * K + k];
        acc[0] += e_obs - lowest + log(total);
        for (int k = 0; k < K; ++k) acc[1 + k] += phi[obs * K + k] - mean[k];
        int r = 1 + K;
        for (int a = 0; a < K; ++a)
            for (int b = a; b < K; ++b, ++r) {
                float cov = 0.0f;
                for (int o = 0; o < NOPT; ++o)
                    cov += energy[o] / total * (phi[o * K + a] - mean[a]) * (phi[o * K + b] - mean[b]);
                acc[r] += cov;
            }
    }
    for (int r = 0; r < ROW; ++r) out[item * ROW + r] = acc[r];
}

/* The smooth kind's pixel sites, theta = (a, c) = (alpha, 1) / T: the conditional of f_i is Gaussian,
 * per component with precision 2 A and mean m = B / A, A = a gamma + c n, B = a gamma g + c s (n bonded
 * neighbours, s the sum of their values). With r = f - m and u = dB - m dA = (gamma (g - m), s - n m),
 * -log p = A r^2 - (NCOMP / 2) log(A / pi) has gradient dA r^2 - 2 r u - (NCOMP / 2) dA / A and Hessian
 * 2 u u' / A + (NCOMP / 2) dA dA' / A^2: written with differences, so float32 loses nothing to
 * cancellation when the field's values are large. A site with A <= 0 (a theta off the domain) makes the
 * value +inf; a site with no data and no bond has no conditional and adds nothing. Rows of 6. */
__kernel void gaussian_terms(__global const float *f, __global const float *g, __global const float *gamma,
                             __global const uchar *lh, __global const uchar *lv, __global const uchar *valid,
                             float a, float c, long W, long H, __global float *out)
{
    long item = get_global_id(0);
    long first = item * CHUNK, sites = W * H;
    if (first >= sites) return;
    float acc[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (long i = first; i < min(first + CHUNK, sites); ++i) {
        long x = i % W, y = i / W, nb[4];
        int keep[4];
        bonds(lh, lv, x, y, i, W, H, nb, keep);
        float n = (float)(keep[0] + keep[1] + keep[2] + keep[3]), weight = gamma[i];
        if (!scored(valid, i, nb, keep) || (n == 0.0f && weight <= 0.0f)) continue;
        float A = a * weight + c * n;
        if (!(A > 0.0f)) { acc[0] = INFINITY; continue; }
        float dA[2] = {weight, n}, hn = 0.5f * NCOMP;
        acc[0] -= hn * log(A / M_PI_F);
        acc[1] -= hn * dA[0] / A;
        acc[2] -= hn * dA[1] / A;
        acc[3] += hn * dA[0] * dA[0] / (A * A);
        acc[4] += hn * dA[0] * dA[1] / (A * A);
        acc[5] += hn * dA[1] * dA[1] / (A * A);
        for (int comp = 0; comp < NCOMP; ++comp) {
            float gi = weight > 0.0f ? g[i * NCOMP + comp] : 0.0f, s = 0.0f;
            for (int m = 0; m < 4; ++m) s += keep[m] ? f[nb[m] * NCOMP + comp] : 0.0f;
            float mean = (a * weight * gi + c * s) / A, r = f[i * NCOMP + comp] - mean, u[2];
            u[0] = weight * (gi - mean);
            u[1] = 0.0f;
            for (int m = 0; m < 4; ++m) u[1] += keep[m] ? f[nb[m] * NCOMP + comp] - mean : 0.0f;
            acc[0] += A * r * r;
            acc[1] += dA[0] * r * r - 2.0f * r * u[0];
            acc[2] += dA[1] * r * r - 2.0f * r * u[1];
            acc[3] += 2.0f * u[0] * u[0] / A;
            acc[4] += 2.0f * u[0] * u[1] / A;
            acc[5] += 2.0f * u[1] * u[1] / A;
        }
    }
    for (int r = 0; r < 6; ++r) out[item * 6 + r] = acc[r];
}
