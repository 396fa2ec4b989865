/* mrf.cl: line-process Markov Random Fields, seed sections "The integration stage and MRF", "MRF
 * models", "Organization of integration" and "Algorithms: Deterministic and stochastic".
 *
 * Energy (equations (10)-(12); vmcl/mrf/energy.py is its NumPy twin and documents it in full):
 *   U(f, l) = sum_i w_i |f_i - g_i|^2                       w_i = alpha * gamma_i (0: no data)
 *           + sum_<ij> rho(f_i, f_j) (1 - l_ij)             rho = |f_i - f_j|^2 (smooth) or kappa [f_i != f_j]
 *           + sum_<ij> l_ij b_ij                            b: central clique, lowered by brightness edges
 *           + sum_vertices table[arms]                      the four line sites meeting at a lattice corner
 *           + par * sum l l'                                parallel neighbours (doubled lines)
 *
 * Layout: f and g are H x W x NCOMP interleaved; line fields are padded to H x W: lh[y, x] lies between
 * pixels (y, x) and (y, x + 1) (last column unused), lv[y, x] between (y, x) and (y + 1, x) (last row
 * unused). The vertex (y, x), for 0 <= y < H - 1 and 0 <= x < W - 1, is the corner shared by pixels
 * (y, x), (y, x + 1), (y + 1, x), (y + 1, x + 1); its arms are up = lh[y, x] (bit 0), down = lh[y + 1, x]
 * (bit 1), left = lv[y, x] (bit 2), right = lv[y, x + 1] (bit 3). Border corners have no clique, so a
 * line pays nothing where it leaves the image.
 *
 * Colouring (a coding in Besag's sense): a site's conditional depends only on sites it shares a clique
 * with. For f those are its 4-neighbours (and the lines, fixed while f is updated): the checkerboard
 * (x + y) & 1 gives two colours. A line site shares cliques with the other arms of its two end vertices
 * and with its two parallel neighbours; lh[y, x] meets lh[y +- 1, x] and lh[y, x +- 1] (other parity)
 * and lv sites of both parities, so the lines take four colours: (type, (x + y) & 1) with type 0 = lh,
 * 1 = lv. Sites of one colour are conditionally independent given the rest, so updating them at once
 * is exactly a sequence of single-site updates. A launch covers one colour, SITES (4) of its sites per
 * work-item along a row; a sweep runs the four line colours, then the two f colours (lattice.py).
 *
 * Defines: NCOMP (1..4 components sharing one line process), KIND (0 smooth, 1 constant), NLEVELS
 * (the levels of the constant kind), MODE (0 heat-bath sample, 1 conditional mode (ICM), 2 mean field).
 */
#include "vmcl.h"
#include "philox.h"

#define MODE_SAMPLE 0
#define MODE_ICM 1
#define MODE_MEAN 2

/* Counter word 2: which colour of the sweep drew the block (f colours 0, 1; line colours 2 to 5), so
 * the groups of different colours, which share (row, group) numbers, never share random words. */
#define PHASE_F 0u
#define PHASE_LINES 2u

/* rho(f_i, f_j): the smoothness cost of the bond between two pixels when no line breaks it. */
inline float bond_cost(__global const float *f, long i, long j, float kappa)
{
#if KIND == 0
    float s = 0.0f;
    for (int c = 0; c < NCOMP; ++c) {
        float d = f[i * NCOMP + c] - f[j * NCOMP + c];
        s += d * d;
    }
    return s;
#else
    return f[i] != f[j] ? kappa : 0.0f;
#endif
}

/* Change of a vertex clique's potential when the arm at `bit` turns on, the other three arms (bits ba,
 * bb, bc) being pa, pb, pc: the table difference for 0/1 arms (sampling, ICM), its expectation with the
 * arms on independently with probabilities pa, pb, pc (mean field). */
inline float vertex_delta(__constant float *table, int bit, int ba, float pa, int bb, float pb, int bc,
                          float pc)
{
#if MODE != MODE_MEAN
    int rest = ((pa != 0.0f) << ba) | ((pb != 0.0f) << bb) | ((pc != 0.0f) << bc);
    return table[rest | (1 << bit)] - table[rest];
#else
    /* The expectation is multilinear in (pa, pb, pc): trilinear interpolation of the 8 corner values. */
    float d[8];
#pragma unroll
    for (int m = 0; m < 8; ++m) {
        int rest = ((m & 1) << ba) | (((m >> 1) & 1) << bb) | (((m >> 2) & 1) << bc);
        d[m] = table[rest | (1 << bit)] - table[rest];
    }
    float d0 = mix(mix(d[0], d[1], pa), mix(d[2], d[3], pa), pb);
    float d1 = mix(mix(d[4], d[5], pa), mix(d[6], d[7], pa), pb);
    return mix(d0, d1, pc);
#endif
}

/* ---------------------------------------------------------------------------------- preparation */

/* Clean data: NaN components (no value) become weight 0. w = alpha * confidence (1 when absent).
 * f0 holds the data where it has weight and NaN elsewhere, for the fill below. */
__kernel void prepare(__global const float *data, __global const float *confidence, int has_confidence,
                      float alpha, __global float *g, __global float *w, __global float *f0, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float weight = has_confidence ? confidence[i] : 1.0f;
    for (int c = 0; c < NCOMP; ++c)
        if (!isfinite(data[i * NCOMP + c])) weight = 0.0f;
    w[i] = alpha * weight;
    for (int c = 0; c < NCOMP; ++c) {
        float v = weight > 0.0f ? data[i * NCOMP + c] : 0.0f;
        g[i * NCOMP + c] = v;
        f0[i * NCOMP + c] = weight > 0.0f ? v : NAN;
    }
}

/* One step of a jump fill of the starting field where there is no data: an empty pixel takes the mean
 * of the filled pixels among its 8 neighbours at distance `step`. Steps 1, 2, 4, ... reach any gap in
 * log2 of its size; the samplers then forget the start. */
__kernel void fill_step(__global const float *in, __global float *out, long step, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    if (!isnan(in[i * NCOMP])) {
        for (int c = 0; c < NCOMP; ++c) out[i * NCOMP + c] = in[i * NCOMP + c];
        return;
    }
    float sum[NCOMP];
    for (int c = 0; c < NCOMP; ++c) sum[c] = 0.0f;
    int n = 0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            long xx = x + dx * step, yy = y + dy * step;
            if ((dx == 0 && dy == 0) || xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
            long j = yy * W + xx;
            if (isnan(in[j * NCOMP])) continue;
            for (int c = 0; c < NCOMP; ++c) sum[c] += in[j * NCOMP + c];
            ++n;
        }
    for (int c = 0; c < NCOMP; ++c) out[i * NCOMP + c] = n ? sum[c] / (float)n : NAN;
}

/* The start of the constant kind: the nearest level (NaN, where nothing was filled, to level 0). */
__kernel void quantise(__global float *f, __constant float *levels, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float v = f[i], best = levels[0];
    for (int k = 1; k < NLEVELS; ++k)
        if (fabs(levels[k] - v) < fabs(best - v)) best = levels[k];
    f[i] = best;
}

/* Central line costs (equation (12)): b = beta * (line_cost - edge_gain * e), e = 1 where a brightness
 * edge pixel lies on either side of the site; with require_edge, +inf (the line is forbidden) where no
 * edge pixel lies within `radius` (Chebyshev) of either pixel. Unused padded sites get +inf. */
inline float edge_near(__global const uchar *edges, long x, long y, long radius, long W, long H)
{
    for (long yy = max(y - radius, 0L); yy <= min(y + radius, H - 1); ++yy)
        for (long xx = max(x - radius, 0L); xx <= min(x + radius, W - 1); ++xx)
            if (edges[yy * W + xx]) return 1.0f;
    return 0.0f;
}

__kernel void line_costs(__global const uchar *edges, int has_edges, float cost, float gain,
                         int require_edge, long radius, __global float *bh, __global float *bv, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    for (int type = 0; type < 2; ++type) {
        long x2 = x + (type == 0), y2 = y + (type == 1);
        float b = INFINITY;
        if (x2 < W && y2 < H) {
            b = cost;
            if (has_edges) {
                long j = y2 * W + x2;
                if (edges[i] || edges[j]) b -= gain;
                else if (require_edge && !edge_near(edges, x, y, radius, W, H)
                         && !edge_near(edges, x2, y2, radius, W, H))
                    b = INFINITY;
            }
        }
        (type == 0 ? bh : bv)[i] = b;
    }
}

__kernel void set_value(__global float *a, float value, long n)
{
    long i = get_global_id(0);
    if (i < n) a[i] = value;
}

/* The four neighbours of pixel i at clamped indices, with the weights 1 - l of their bonds; a missing
 * neighbour gets weight 0. No branches, so the compiler can vectorise across work-items. */
inline void neighbours(__global const float *lh, __global const float *lv, int x, int y, int i, int W, int H,
                       int *nb, float *keep)
{
    nb[0] = x > 0 ? i - 1 : i;
    nb[1] = x < W - 1 ? i + 1 : i;
    nb[2] = y > 0 ? i - W : i;
    nb[3] = y < H - 1 ? i + W : i;
    float left = lh[nb[0]], up = lv[nb[2]];
    keep[0] = x > 0 ? 1.0f - left : 0.0f;
    keep[1] = x < W - 1 ? 1.0f - lh[i] : 0.0f;
    keep[2] = y > 0 ? 1.0f - up : 0.0f;
    keep[3] = y < H - 1 ? 1.0f - lv[i] : 0.0f;
}

/* ------------------------------------------------------------------------------------ f updates */

/* f at one site: heat bath (the conditional is Gaussian for the smooth kind, discrete over the levels
 * for the constant kind), its mode (ICM) or, with line expectations, the mean-field fixed point. `z`
 * holds NCOMP standard normals (smooth kind), `u` a uniform (constant kind). A smooth site with no data
 * and all four bonds broken has no conditional and keeps its value. */
inline void f_site(__global float *f, __global const float *g, __global const float *w,
                   __global const float *lh, __global const float *lv, __constant float *levels, float kappa,
                   float T, int x, int y, int W, int H, const float *z, float u)
{
    int i = y * W + x;
    int nb[4];
    float keep[4];
    neighbours(lh, lv, x, y, i, W, H, nb, keep);
#if KIND == 0
    float a = w[i], b[NCOMP];
    for (int c = 0; c < NCOMP; ++c) b[c] = w[i] * g[i * NCOMP + c];
    for (int k = 0; k < 4; ++k) {
        a += keep[k];
        for (int c = 0; c < NCOMP; ++c) b[c] += keep[k] * f[nb[k] * NCOMP + c];
    }
    if (a <= 0.0f) return;
#if MODE == MODE_SAMPLE
    float sd = sqrt(T / (2.0f * a));
    for (int c = 0; c < NCOMP; ++c) f[i * NCOMP + c] = b[c] / a + sd * z[c];
#else
    for (int c = 0; c < NCOMP; ++c) f[i * NCOMP + c] = b[c] / a;
#endif
#else
    float energy[NLEVELS];
    float lowest = INFINITY;
    int best = 0;
    for (int k = 0; k < NLEVELS; ++k) {
        float d = levels[k] - g[i];
        float e = w[i] * d * d;
        for (int m = 0; m < 4; ++m) e += levels[k] != f[nb[m]] ? kappa * keep[m] : 0.0f;
        energy[k] = e;
        if (e < lowest) { lowest = e; best = k; }
    }
#if MODE == MODE_SAMPLE
    float total = 0.0f;
    for (int k = 0; k < NLEVELS; ++k) {
        energy[k] = exp(-(energy[k] - lowest) / T);
        total += energy[k];
    }
    float target = u * total;
    best = NLEVELS - 1;
    for (int k = 0; k < NLEVELS - 1; ++k) {
        target -= energy[k];
        if (target < 0.0f) { best = k; break; }
    }
#endif
    f[i] = levels[best];
#endif
}

/* A work-item updates SITES sites of one colour along a row, x = 2 (SITES gx + k) + ((y + colour) & 1),
 * and keys its Philox blocks by its group (y * groups + gx): one block of four words serves four sites,
 * so the generator's cost is shared (the counter still names the sites, whatever the local size). */
#define SITES 4
#define GROUPS(W) ((((W) + 1) / 2 + SITES - 1) / SITES)

/* f at the pixels of one checkerboard colour; the smooth kind draws its normals by Box-Muller, two per
 * pair of words, NCOMP blocks per group (counter word 3 numbers the block). */
__kernel void f_update(__global float *f, __global const float *g, __global const float *w,
                       __global const float *lh, __global const float *lv, __constant float *levels,
                       float kappa, float T, uint sweep, uint2 key, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1), group = get_global_id(0), groups = GROUPS(W);
    if (group >= groups || y >= H) return;
    float z[SITES * NCOMP], u[SITES];
    for (int k = 0; k < SITES; ++k) u[k] = 0.0f;
    for (int k = 0; k < SITES * NCOMP; ++k) z[k] = 0.0f;
#if MODE == MODE_SAMPLE && KIND == 0
    for (int block = 0; block < NCOMP; ++block) {
        uint4 r = philox4x32_10((uint4)((uint)(y * groups + group), sweep, PHASE_F + colour, (uint)block), key);
        float r0 = native_sqrt(-2.0f * native_log(philox_uniform(r.x))), a0 = 2.0f * M_PI_F * philox_uniform(r.y);
        float r1 = native_sqrt(-2.0f * native_log(philox_uniform(r.z))), a1 = 2.0f * M_PI_F * philox_uniform(r.w);
        z[4 * block] = r0 * native_cos(a0);
        z[4 * block + 1] = r0 * native_sin(a0);
        z[4 * block + 2] = r1 * native_cos(a1);
        z[4 * block + 3] = r1 * native_sin(a1);
    }
#elif MODE == MODE_SAMPLE
    philox_uniforms((uint4)((uint)(y * groups + group), sweep, PHASE_F + colour, 0u), key, u);
#endif
    for (int k = 0; k < SITES; ++k) {
        int x = 2 * (SITES * group + k) + ((y + colour) & 1);
        if (x < W) f_site(f, g, w, lh, lv, levels, kappa, T, x, y, W, H, z + k * NCOMP, u[k]);
    }
}

/* Mean field for the constant kind: q[i, k] is the probability that pixel i takes level k; the Potts
 * interaction is replaced by its expectation kappa (1 - q_j(k)) under the neighbour's distribution. */
__kernel void q_update(__global float *q, __global const float *g, __global const float *w,
                       __global const float *lh, __global const float *lv, __constant float *levels,
                       float kappa, float T, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1);
    int x = 2 * (int)get_global_id(0) + ((y + colour) & 1);
    if (x >= W || y >= H) return;
    int i = y * W + x;
    int nb[4];
    float keep[4];
    neighbours(lh, lv, x, y, i, W, H, nb, keep);
    float energy[NLEVELS];
    float lowest = INFINITY;
    for (int k = 0; k < NLEVELS; ++k) {
        float d = levels[k] - g[i];
        float e = w[i] * d * d;
        for (int m = 0; m < 4; ++m) e += kappa * keep[m] * (1.0f - q[nb[m] * NLEVELS + k]);
        energy[k] = e;
        lowest = min(lowest, e);
    }
    float total = 0.0f;
    for (int k = 0; k < NLEVELS; ++k) {
        energy[k] = exp(-(energy[k] - lowest) / T);
        total += energy[k];
    }
    for (int k = 0; k < NLEVELS; ++k) q[i * NLEVELS + k] = energy[k] / total;
}

/* q from a field of levels: all the mass on the pixel's own level. */
__kernel void q_init(__global float *q, __global const float *f, __constant float *levels, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    for (int k = 0; k < NLEVELS; ++k) q[i * NLEVELS + k] = levels[k] == f[i] ? 1.0f : 0.0f;
}

/* The field of the most probable level of each pixel (mean field) or of the most frequent one (MPM). */
__kernel void levels_mode(__global const float *weights, __global float *f, __constant float *levels, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int best = 0;
    for (int k = 1; k < NLEVELS; ++k)
        if (weights[i * NLEVELS + k] > weights[i * NLEVELS + best]) best = k;
    f[i] = levels[best];
}

/* --------------------------------------------------------------------------------- line updates */

/* Line sites of colour (type, parity): heat bath from the exact conditional, its mode (ICM), or the
 * mean-field expectation sigma(-dE / T) with the neighbours' expectations in the cliques. dE is the
 * energy of l = 1 minus that of l = 0 over every clique that holds the site: the broken bond, the
 * central cost, both end vertices and both parallel pairs (the seed's warning: non-central cliques count).
 * Neighbours are read at clamped indices and masked, without branches, so the compiler can vectorise
 * across work-items. */
inline float line_bond(__global const float *f, __global const float *q, int i, int j, float kappa)
{
#if KIND == 1 && MODE == MODE_MEAN
    float same = 0.0f;
    for (int k = 0; k < NLEVELS; ++k) same += q[i * NLEVELS + k] * q[j * NLEVELS + k];
    return kappa * (1.0f - same);
#else
    return bond_cost(f, i, j, kappa);
#endif
}

inline void line_set(__global float *l, int i, float dE, float T, float u)
{
#if MODE == MODE_ICM
    l[i] = dE < 0.0f ? 1.0f : 0.0f;
#else
    /* Clamped so that a forbidden line (dE = +inf) gets probability e^-80, never NaN from native_exp. */
    float odds = native_exp(clamp(dE / T, -80.0f, 80.0f));
#if MODE == MODE_SAMPLE
    l[i] = u * (1.0f + odds) < 1.0f ? 1.0f : 0.0f;
#else
    l[i] = 1.0f / (1.0f + odds);
#endif
#endif
}

/* dE of the lh site (y, x), between (y, x) and (y, x + 1). */
inline float line_h_delta(__global const float *lh, __global const float *lv, __global const float *f,
                          __global const float *q, __global const float *bh, __constant float *table,
                          float parallel, float kappa, int x, int y, int W, int H)
{
    int i = y * W + x;
    int above = y > 0 ? i - W : i, below = y < H - 1 ? i + W : i;
    float dE = bh[i] - line_bond(f, q, i, i + 1, kappa);
    float top = vertex_delta(table, 1, 0, lh[above], 2, lv[above], 3, lv[above + 1]);
    float bottom = vertex_delta(table, 0, 1, lh[below], 2, lv[i], 3, lv[i + 1]);
    dE += (y > 0 ? top : 0.0f) + (y < H - 1 ? bottom : 0.0f);
    float left = lh[x > 0 ? i - 1 : i];
    return dE + parallel * ((x > 0 ? left : 0.0f) + (x + 1 < W - 1 ? lh[i + 1] : 0.0f));
}

/* dE of the lv site (y, x), between (y, x) and (y + 1, x). */
inline float line_v_delta(__global const float *lh, __global const float *lv, __global const float *f,
                          __global const float *q, __global const float *bv, __constant float *table,
                          float parallel, float kappa, int x, int y, int W, int H)
{
    int i = y * W + x;
    int left = x > 0 ? i - 1 : i, up = y > 0 ? i - W : i;
    float dE = bv[i] - line_bond(f, q, i, i + W, kappa);
    float west = vertex_delta(table, 3, 0, lh[left], 1, lh[left + W], 2, lv[left]);
    float east = vertex_delta(table, 2, 0, lh[i], 1, lh[i + W], 3, lv[i + 1]);
    dE += (x > 0 ? west : 0.0f) + (x < W - 1 ? east : 0.0f);
    return dE + parallel * ((y > 0 ? lv[up] : 0.0f) + (y + 1 < H - 1 ? lv[i + W] : 0.0f));
}

/* The line sites of one colour: type 0 (lh) or 1 (lv), (x + y) & 1 == parity; SITES per work-item. */
__kernel void line_update(__global float *lh, __global float *lv, __global const float *f,
                          __global const float *q, __global const float *bh, __global const float *bv,
                          __constant float *table, float parallel, float kappa, float T, uint sweep,
                          uint2 key, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1), group = get_global_id(0), groups = GROUPS(W);
    int type = colour >> 1, parity = colour & 1;
    if (group >= groups || y >= H - type) return;
    float u[SITES] = {0.0f, 0.0f, 0.0f, 0.0f};
#if MODE == MODE_SAMPLE
    philox_uniforms((uint4)((uint)(y * groups + group), sweep, PHASE_LINES + colour, 0u), key, u);
#endif
    for (int k = 0; k < SITES; ++k) {
        int x = 2 * (SITES * group + k) + ((y + parity) & 1);
        if (type == 0 && x < W - 1)
            line_set(lh, y * W + x, line_h_delta(lh, lv, f, q, bh, table, parallel, kappa, x, y, W, H), T, u[k]);
        else if (type == 1 && x < W)
            line_set(lv, y * W + x, line_v_delta(lh, lv, f, q, bv, table, parallel, kappa, x, y, W, H), T, u[k]);
    }
}

/* ------------------------------------------------------------------------ estimates and energy */

/* Marroquin's estimators: running sums of f (smooth) or level counts (constant) and of the lines. */
__kernel void accumulate(__global const float *f, __global const float *lh, __global const float *lv,
                         __global float *sum_f, __global float *sum_h, __global float *sum_v,
                         __constant float *levels, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
#if KIND == 0
    for (int c = 0; c < NCOMP; ++c) sum_f[i * NCOMP + c] += f[i * NCOMP + c];
#else
    for (int k = 0; k < NLEVELS; ++k)
        if (levels[k] == f[i]) sum_f[i * NLEVELS + k] += 1.0f;
#endif
    sum_h[i] += lh[i];
    sum_v[i] += lv[i];
}

/* a / count for the posterior mean; lines on where their marginal exceeds 1/2 (count 1 thresholds
 * mean-field expectations). */
__kernel void scale_and_threshold(__global float *sum_f, __global float *sum_h, __global float *sum_v,
                                  float count, int scale_f, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    if (scale_f)
        for (int c = 0; c < NCOMP; ++c) sum_f[i * NCOMP + c] /= count;
    sum_h[i] = sum_h[i] > 0.5f * count ? 1.0f : 0.0f;
    sum_v[i] = sum_v[i] > 0.5f * count ? 1.0f : 0.0f;
}

/* Each pixel's share of U(f, l) for 0/1 lines: its data term, its right and down bonds and line sites,
 * the vertex below-right of it and the parallel pairs to its right (lh) and below (lv). */
__kernel void site_energy(__global const float *f, __global const float *g, __global const float *w,
                          __global const float *lh, __global const float *lv, __global const float *bh,
                          __global const float *bv, __constant float *table, float parallel, float kappa,
                          __global float *out, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float e = 0.0f;
    for (int c = 0; c < NCOMP; ++c) {
        float d = f[i * NCOMP + c] - g[i * NCOMP + c];
        e += w[i] * d * d;
    }
    if (x < W - 1) e += lh[i] != 0.0f ? bh[i] : bond_cost(f, i, i + 1, kappa);
    if (y < H - 1) e += lv[i] != 0.0f ? bv[i] : bond_cost(f, i, i + W, kappa);
    if (x < W - 1 && y < H - 1) {
        int arms = (lh[i] != 0.0f) | ((lh[i + W] != 0.0f) << 1) | ((lv[i] != 0.0f) << 2)
                 | ((lv[i + 1] != 0.0f) << 3);
        e += table[arms];
    }
    if (x + 1 < W - 1 && lh[i] != 0.0f && lh[i + 1] != 0.0f) e += parallel;
    if (y + 1 < H - 1 && lv[i] != 0.0f && lv[i + W] != 0.0f) e += parallel;
    out[i] = e;
}

/* Padded H x W line fields to the public shapes: lh to H x (W - 1), lv to (H - 1) x W. */
__kernel void unpad(__global const float *lh, __global const float *lv, __global uchar *line_h,
                    __global uchar *line_v, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    if (x < W - 1) line_h[y * (W - 1) + x] = lh[y * W + x] != 0.0f;
    if (y < H - 1) line_v[y * W + x] = lv[y * W + x] != 0.0f;
}

/* Raw Philox4x32-10 blocks for the known-answer test: out[k] = philox(counters[k], keys[k]). */
__kernel void philox_blocks(__global const uint4 *counters, __global const uint2 *keys, __global uint4 *out,
                            long n)
{
    long k = get_global_id(0);
    if (k < n) out[k] = philox4x32_10(counters[k], keys[k]);
}
