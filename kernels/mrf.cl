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
 * is exactly a sequence of single-site updates. A launch covers one colour, SITES (16) of its sites per
 * work-item along a row as vector lanes; a sweep runs the four line colours, then the two f colours (lattice.py).
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

/* rho(f_i, f_j), bond_cost: shared with the pseudolikelihood's features. */
#include "bond.h"

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

/* A warm start (vmcl.mrf.restore's start): f takes the given field wherever all its components hold a
 * value, and keeps the filled data elsewhere. */
__kernel void start_from(__global const float *start, __global float *f, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    int complete = 1;
    for (int c = 0; c < NCOMP; ++c) complete &= isfinite(start[i * NCOMP + c]);
    if (complete)
        for (int c = 0; c < NCOMP; ++c) f[i * NCOMP + c] = start[i * NCOMP + c];
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

/* The neighbourhood of require_edge, in two passes since a Chebyshev square is separable: near_rows gives
 * each pixel its distance along its row to the nearest edge pixel (W where the row has none), one
 * work-item per row; near_columns marks the pixels with a row within `radius` whose distance is within
 * `radius`, one work-item per column. O(H W) for any radius, where scanning each pixel's square would
 * cost (2 radius + 1)^2 (vmcl/mrf/energy.py's _dilate is the host's twin). */
__kernel void near_rows(__global const uchar *edges, __global int *distance, long W, long H)
{
    long y = get_global_id(0);
    if (y >= H) return;
    __global const uchar *e = edges + y * W;
    __global int *d = distance + y * W;
    long last = -1;
    for (long x = 0; x < W; ++x) {
        if (e[x]) last = x;
        d[x] = last < 0 ? INT_MAX : (int)(x - last);  /* no edge in the row: beyond any radius */
    }
    last = -1;
    for (long x = W - 1; x >= 0; --x) {
        if (e[x]) last = x;
        if (last >= 0 && last - x < d[x]) d[x] = (int)(last - x);
    }
}

__kernel void near_columns(__global const int *distance, long radius, __global uchar *near, long W, long H)
{
    long x = get_global_id(0);
    if (x >= W) return;
    long last = -1;  /* the latest row so far whose distance is within the radius */
    for (long y = 0; y < H; ++y) {
        if (distance[y * W + x] <= radius) last = y;
        near[y * W + x] = last >= 0 && y - last <= radius;
    }
    last = -1;
    for (long y = H - 1; y >= 0; --y) {
        if (distance[y * W + x] <= radius) last = y;
        if (last >= 0 && last - y <= radius) near[y * W + x] = 1;
    }
}

/* Central line costs (equation (12)): b = beta * (line_cost - edge_gain * e), e = 1 where a brightness
 * edge pixel lies on either side of the site; with require_edge, +inf (the line is forbidden) where no
 * edge pixel lies within the radius of either pixel (`near`, from the passes above; read only with
 * require_edge and edges). Unused padded sites get +inf. */
__kernel void line_costs(__global const uchar *edges, int has_edges, float cost, float gain,
                         int require_edge, __global const uchar *near, __global float *bh, __global float *bv,
                         long W, long H)
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
                else if (require_edge && !near[i] && !near[j])
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

/* ------------------------------------------------------------------------------------ f updates */

/* A work-item updates SITES (16) sites of one colour along a row, x = 2 (SITES gx + k) + ((y + colour) & 1),
 * k = 0..15, as float16 lanes in straight-line vector code (no per-site branches: masks and select), and
 * keys its Philox blocks by its group (y * groups + gx, block number in counter word 3): four blocks,
 * computed together on uint4 lanes, give the 16 uniforms of 16 sites (the counter still names the
 * sites, whatever the local size). Sites past the row's end are computed and not stored. */
#define SITES 16
#define GROUPS(W) ((((W) + 1) / 2 + SITES - 1) / SITES)
#define LANES ((int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))

/* p[start + stride k], k = 0..15: two contiguous vector loads for the stride 2 of a colour when they
 * lie inside the n floats of the buffer, else a gather at clamped indices (values that lanes outside
 * the lattice get are masked by the callers). */
inline float16 load_sites(__global const float *p, int start, int stride, int n)
{
    if (stride == 2 && start >= 0 && start + 2 * SITES <= n) {
        float16 a = vload16(0, p + start), b = vload16(0, p + start + 16);
        return (float16)(a.even, b.even);
    }
    float t[SITES];
#pragma unroll
    for (int k = 0; k < SITES; ++k) t[k] = p[clamp(start + stride * k, 0, n - 1)];
    return vload16(0, t);
}

/* p[start + 2 k] = v lane k for the lanes with x0 + 2 k < limit. */
inline void store_sites(__global float *p, int start, float16 v, int x0, int limit)
{
    float t[SITES];
    vstore16(v, 0, t);
#pragma unroll
    for (int k = 0; k < SITES; ++k)
        if (x0 + 2 * k < limit) p[start + 2 * k] = t[k];
}

#define ZERO16 ((float16)(0.0f))
#define MASK16(c) ((c) ? (int16)(-1) : (int16)(0))

/* Each of the 16 sites' four bonds (left, right, up, down) weighted by `scale` times 1 - l, the bond's
 * (expected) keeping, and 0 past the border, where the neighbour, read at a clamped index, must not count. */
inline void bond_weights16(__global const float *lh, __global const float *lv, int x0, int y, int base, int W,
                           int H, int n, float scale, float16 *keep)
{
    int16 xs = x0 + 2 * LANES;
    keep[0] = select(ZERO16, scale * (1.0f - load_sites(lh, base - 1, 2, n)), xs > 0);
    keep[1] = select(ZERO16, scale * (1.0f - load_sites(lh, base, 2, n)), xs < W - 1);
    keep[2] = y > 0 ? scale * (1.0f - load_sites(lv, base - W, 2, n)) : ZERO16;
    keep[3] = y < H - 1 ? scale * (1.0f - load_sites(lv, base, 2, n)) : ZERO16;
}

/* f at the pixels of one checkerboard colour. Smooth kind: the Gaussian conditional (heat bath), its
 * mean (ICM, mean field), NCOMP components each from four blocks (counter word 3: 4 c + j) whose 16
 * uniforms give 16 normals by Box-Muller (radii from words 0, 1, angles from words 2, 3); a site with no
 * data and all four bonds broken keeps its value. Constant kind: the discrete conditional over the levels
 * (heat bath) or its mode (ICM), on the same lanes. */
__kernel void f_update(__global float *f, __global const float *g, __global const float *w,
                       __global const float *lh, __global const float *lv, __constant float *levels,
                       float kappa, float T, uint sweep, uint2 key, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1), group = get_global_id(0), groups = GROUPS(W);
    if (group >= groups || y >= H) return;
    int n = W * H, x0 = 2 * SITES * group + ((y + colour) & 1), base = y * W + x0;
#if KIND == 0
    float16 wi = load_sites(w, base, 2, n), keep[4];
    bond_weights16(lh, lv, x0, y, base, W, H, n, 1.0f, keep);
    float16 a = wi + keep[0] + keep[1] + keep[2] + keep[3];
    int16 frozen = a <= 0.0f;
#if MODE == MODE_SAMPLE
    float16 sd = sqrt(T / (2.0f * a));
#endif
    for (int c = 0; c < NCOMP; ++c) {
        int nf = n * NCOMP, s = 2 * NCOMP;
        float16 old = load_sites(f, base * NCOMP + c, s, nf);
        float16 b = wi * load_sites(g, base * NCOMP + c, s, nf);
        b += keep[0] * load_sites(f, (base - 1) * NCOMP + c, s, nf);
        b += keep[1] * load_sites(f, (base + 1) * NCOMP + c, s, nf);
        b += keep[2] * load_sites(f, (base - W) * NCOMP + c, s, nf);
        b += keep[3] * load_sites(f, (base + W) * NCOMP + c, s, nf);
        float16 value = b / a;
#if MODE == MODE_SAMPLE
        float16 u = philox_uniforms16((uint)(y * groups + group), sweep, PHASE_F + colour, 4u * c, key);
        float8 radius = native_sqrt(-2.0f * native_log(u.lo)), angle = 2.0f * M_PI_F * u.hi;
        value += sd * (float16)(radius * native_cos(angle), radius * native_sin(angle));
#endif
        float t[SITES];
        vstore16(select(value, old, frozen), 0, t);
#pragma unroll
        for (int k = 0; k < SITES; ++k)
            if (x0 + 2 * k < W) f[(base + 2 * k) * NCOMP + c] = t[k];
    }
#else
    float16 wi = load_sites(w, base, 2, n), gi = load_sites(g, base, 2, n), keep[4];
    bond_weights16(lh, lv, x0, y, base, W, H, n, kappa, keep);  /* kappa where a bond is kept */
    float16 f0 = load_sites(f, base - 1, 2, n), f1 = load_sites(f, base + 1, 2, n);
    float16 f2 = load_sites(f, base - W, 2, n), f3 = load_sites(f, base + W, 2, n);
    float16 energy[NLEVELS];
    float16 lowest = (float16)(INFINITY);
    int16 best = (int16)(0);
#pragma unroll
    for (int k = 0; k < NLEVELS; ++k) {
        float16 d = levels[k] - gi;
        float16 e = wi * d * d;
        e += select(ZERO16, keep[0], levels[k] != f0);
        e += select(ZERO16, keep[1], levels[k] != f1);
        e += select(ZERO16, keep[2], levels[k] != f2);
        e += select(ZERO16, keep[3], levels[k] != f3);
        energy[k] = e;
        int16 lower = e < lowest;
        lowest = select(lowest, e, lower);
        best = select(best, (int16)(k), lower);
    }
#if MODE == MODE_SAMPLE
    /* Heat bath: the first level whose cumulative weight passes u times the total. Site 4 p + j draws
     * word j of block p; philox_uniforms16 gives word m of block j in lane 4 m + j. */
    float16 u = philox_uniforms16((uint)(y * groups + group), sweep, PHASE_F + colour, 0u, key);
    u = shuffle(u, (uint16)(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15));
    float16 total = ZERO16;
#pragma unroll
    for (int k = 0; k < NLEVELS; ++k) {
        energy[k] = exp(-(energy[k] - lowest) / T);
        total += energy[k];
    }
    float16 target = u * total;
    int16 found = (int16)(0);
    best = (int16)(NLEVELS - 1);
#pragma unroll
    for (int k = 0; k < NLEVELS - 1; ++k) {
        target -= energy[k];
        int16 hit = (target < 0.0f) & ~found;
        best = select(best, (int16)(k), hit);
        found |= hit;
    }
#endif
    float16 value = (float16)(levels[0]);
#pragma unroll
    for (int k = 1; k < NLEVELS; ++k) value = select(value, (float16)(levels[k]), best == k);
    store_sites(f, base, value, x0, W);
#endif
}

/* Mean field for the constant kind: q[k n + i] (a plane per level, n = W H sites) is the probability
 * that pixel i takes level k; the Potts interaction is replaced by its expectation kappa (1 - q_j(k))
 * under the neighbour's distribution. SITES sites of the colour per work-item as float16 lanes, as
 * f_update: with a plane per level a level's 16 sites are two contiguous loads (an interleaved layout
 * made every read a gather). */
__kernel void q_update(__global float *q, __global const float *g, __global const float *w,
                       __global const float *lh, __global const float *lv, __constant float *levels,
                       float kappa, float T, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1), group = get_global_id(0), groups = GROUPS(W);
    if (group >= groups || y >= H) return;
    int n = W * H, all = n * NLEVELS, x0 = 2 * SITES * group + ((y + colour) & 1), base = y * W + x0;
    float16 wi = load_sites(w, base, 2, n), gi = load_sites(g, base, 2, n), keep[4];
    /* kappa times each bond's expectation of being kept; past the border the neighbour's q, read at a
     * clamped index, is finite whatever it is, and weighted by 0. */
    bond_weights16(lh, lv, x0, y, base, W, H, n, kappa, keep);
    float16 energy[NLEVELS];
    float16 lowest = (float16)(INFINITY);
#pragma unroll
    for (int k = 0; k < NLEVELS; ++k) {
        int plane = k * n + base;
        float16 d = levels[k] - gi;
        float16 e = wi * d * d;
        e += keep[0] * (1.0f - load_sites(q, plane - 1, 2, all));
        e += keep[1] * (1.0f - load_sites(q, plane + 1, 2, all));
        e += keep[2] * (1.0f - load_sites(q, plane - W, 2, all));
        e += keep[3] * (1.0f - load_sites(q, plane + W, 2, all));
        energy[k] = e;
        lowest = fmin(lowest, e);
    }
    float16 total = ZERO16;
#pragma unroll
    for (int k = 0; k < NLEVELS; ++k) {
        energy[k] = exp((lowest - energy[k]) / T);
        total += energy[k];
    }
#pragma unroll
    for (int k = 0; k < NLEVELS; ++k) store_sites(q, k * n + base, energy[k] / total, x0, W);
}

/* q from a field of levels: all the mass on the pixel's own level. */
__kernel void q_init(__global float *q, __global const float *f, __constant float *levels, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    for (int k = 0; k < NLEVELS; ++k) q[k * n + i] = levels[k] == f[i] ? 1.0f : 0.0f;
}

/* The field of the most probable level of each pixel (mean field) or of the most frequent one (MPM);
 * weights hold a plane of n per level. */
__kernel void levels_mode(__global const float *weights, __global float *f, __constant float *levels, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int best = 0;
    for (int k = 1; k < NLEVELS; ++k)
        if (weights[k * n + i] > weights[best * n + i]) best = k;
    f[i] = levels[best];
}

/* --------------------------------------------------------------------------------- line updates */

/* Line sites of colour (type, parity): heat bath from the exact conditional, its mode (ICM), or the
 * mean-field expectation sigma(-dE / T) with the neighbours' expectations in the cliques. dE is the
 * energy of l = 1 minus that of l = 0 over every clique that holds the site: the broken bond, the
 * central cost, both end vertices and both parallel pairs (the seed's warning: non-central cliques count).
 * Neighbours are read at clamped indices and masked, without branches, so the compiler can vectorise
 * across work-items. */
/* Change of a vertex clique's potential when the arm at `bit` turns on, the other three arms (bits ba,
 * bb, bc) being pa, pb, pc, on 16 sites: vertex_corners gives the 8 table differences d[m] over the
 * other arms' states (m: bit 0 arm a, bit 1 b, bit 2 c), vertex_delta16 picks one by select for 0/1 arms
 * (sampling, ICM), or takes its expectation with the arms on independently with probabilities pa, pb, pc
 * (mean field; multilinear, so trilinear interpolation of the 8 corners). */
inline void vertex_corners(__constant float *table, int bit, int ba, int bb, int bc, float *d)
{
#pragma unroll
    for (int m = 0; m < 8; ++m) {
        int rest = ((m & 1) << ba) | (((m >> 1) & 1) << bb) | (((m >> 2) & 1) << bc);
        d[m] = table[rest | (1 << bit)] - table[rest];
    }
}

inline float16 vertex_delta16(const float *d, float16 pa, float16 pb, float16 pc)
{
#if MODE != MODE_MEAN
    int16 ma = pa != 0.0f, mb = pb != 0.0f, mc = pc != 0.0f;
    float16 e0 = select((float16)(d[0]), (float16)(d[1]), ma), e1 = select((float16)(d[2]), (float16)(d[3]), ma);
    float16 e2 = select((float16)(d[4]), (float16)(d[5]), ma), e3 = select((float16)(d[6]), (float16)(d[7]), ma);
    return select(select(e0, e1, mb), select(e2, e3, mb), mc);
#else
    float16 d0 = mix(mix((float16)(d[0]), (float16)(d[1]), pa), mix((float16)(d[2]), (float16)(d[3]), pa), pb);
    float16 d1 = mix(mix((float16)(d[4]), (float16)(d[5]), pa), mix((float16)(d[6]), (float16)(d[7]), pa), pb);
    return mix(d0, d1, pc);
#endif
}

/* line_bond on 16 sites: pixels base + 2 k and base + 2 k + step. */
inline float16 line_bond16(__global const float *f, __global const float *q, int base, int step, int n,
                           float kappa)
{
#if KIND == 1 && MODE == MODE_MEAN
    float16 same = ZERO16;
    for (int k = 0; k < NLEVELS; ++k)
        same += load_sites(q, k * n + base, 2, n * NLEVELS) * load_sites(q, k * n + base + step, 2, n * NLEVELS);
    return kappa * (1.0f - same);
#elif KIND == 0
    float16 s = ZERO16;
    for (int c = 0; c < NCOMP; ++c) {
        float16 d = load_sites(f, base * NCOMP + c, 2 * NCOMP, n * NCOMP)
                  - load_sites(f, (base + step) * NCOMP + c, 2 * NCOMP, n * NCOMP);
        s += d * d;
    }
    return s;
#else
    return select(ZERO16, (float16)(kappa), load_sites(f, base, 2, n) != load_sites(f, base + step, 2, n));
#endif
}

/* The line sites of one colour: type 0 (lh) or 1 (lv), (x + y) & 1 == parity; SITES per work-item as
 * float16 lanes. Heat bath: l = 1 with probability 1 / (1 + e^(dE / T)) (clamped so that a forbidden
 * line, dE = +inf, gets e^-80, never NaN from native_exp); ICM: dE < 0; mean field: the probability. */
__kernel void line_update(__global float *lh, __global float *lv, __global const float *f,
                          __global const float *q, __global const float *bh, __global const float *bv,
                          __constant float *table, float parallel, float kappa, float T, uint sweep,
                          uint2 key, int colour, long W_, long H_)
{
    int W = (int)W_, H = (int)H_, y = get_global_id(1), group = get_global_id(0), groups = GROUPS(W);
    int type = colour >> 1, parity = colour & 1;
    if (group >= groups || y >= H - type) return;
    int n = W * H, x0 = 2 * SITES * group + ((y + parity) & 1), base = y * W + x0;
    int16 xs = x0 + 2 * LANES;
    float da[8], db[8];
    float16 dE;
    if (type == 0) {
        /* lh (y, x), between (y, x) and (y, x + 1): vertices above (arm down) and below (arm up). */
        vertex_corners(table, 1, 0, 2, 3, da);
        vertex_corners(table, 0, 1, 2, 3, db);
        dE = load_sites(bh, base, 2, n) - line_bond16(f, q, base, 1, n, kappa);
        float16 top = vertex_delta16(da, load_sites(lh, base - W, 2, n), load_sites(lv, base - W, 2, n),
                                     load_sites(lv, base - W + 1, 2, n));
        float16 bottom = vertex_delta16(db, load_sites(lh, base + W, 2, n), load_sites(lv, base, 2, n),
                                        load_sites(lv, base + 1, 2, n));
        dE += (y > 0 ? top : ZERO16) + (y < H - 1 ? bottom : ZERO16);
        float16 left = select(ZERO16, load_sites(lh, base - 1, 2, n), xs > 0);
        float16 right = select(ZERO16, load_sites(lh, base + 1, 2, n), xs + 1 < W - 1);
        dE += parallel * (left + right);
    } else {
        /* lv (y, x), between (y, x) and (y + 1, x): vertices left (arm right) and right (arm left). */
        vertex_corners(table, 3, 0, 1, 2, da);
        vertex_corners(table, 2, 0, 1, 3, db);
        dE = load_sites(bv, base, 2, n) - line_bond16(f, q, base, W, n, kappa);
        float16 west = vertex_delta16(da, load_sites(lh, base - 1, 2, n), load_sites(lh, base + W - 1, 2, n),
                                      load_sites(lv, base - 1, 2, n));
        float16 east = vertex_delta16(db, load_sites(lh, base, 2, n), load_sites(lh, base + W, 2, n),
                                      load_sites(lv, base + 1, 2, n));
        dE += select(ZERO16, west, xs > 0) + select(ZERO16, east, xs < W - 1);
        float16 up = y > 0 ? load_sites(lv, base - W, 2, n) : ZERO16;
        float16 down = y + 1 < H - 1 ? load_sites(lv, base + W, 2, n) : ZERO16;
        dE += parallel * (up + down);
    }
#if MODE == MODE_ICM
    float16 l = select(ZERO16, (float16)(1.0f), dE < 0.0f);
#else
    float16 odds = native_exp(clamp(dE / T, -80.0f, 80.0f));
#if MODE == MODE_SAMPLE
    float16 u = philox_uniforms16((uint)(y * groups + group), sweep, PHASE_LINES + colour, 0u, key);
    float16 l = select(ZERO16, (float16)(1.0f), u * (1.0f + odds) < 1.0f);
#else
    float16 l = 1.0f / (1.0f + odds);
#endif
#endif
    store_sites(type == 0 ? lh : lv, base, l, x0, W - 1 + type);
}

/* ------------------------------------------------------------------------ estimates and energy */

/* Marroquin's estimators: running sums of f (smooth) or level counts (constant, a plane of n per level)
 * and of the lines. */
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
        if (levels[k] == f[i]) sum_f[k * n + i] += 1.0f;
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

/* Raw Philox4x32-10 blocks for the known-answer test: out[k] = philox(counters[k], keys[k]); with
 * `lanes`, the same blocks four at a time through philox4x32_10_x4 (k a multiple of 4 below n). */
__kernel void philox_blocks(__global const uint4 *counters, __global const uint2 *keys, __global uint4 *out,
                            long n)
{
    long k = get_global_id(0);
    if (k < n) out[k] = philox4x32_10(counters[k], keys[k]);
}

__kernel void philox_blocks4(__global const uint4 *counters, uint2 key, __global uint4 *out, long n)
{
    long k = 4 * get_global_id(0);
    if (k + 3 >= n) return;
    uint4 a = counters[k], b = counters[k + 1], c = counters[k + 2], d = counters[k + 3];
    uint4 w0 = (uint4)(a.x, b.x, c.x, d.x), w1 = (uint4)(a.y, b.y, c.y, d.y);
    uint4 w2 = (uint4)(a.z, b.z, c.z, d.z), w3 = (uint4)(a.w, b.w, c.w, d.w);
    philox4x32_10_x4(&w0, &w1, &w2, &w3, key);
    out[k] = (uint4)(w0.x, w1.x, w2.x, w3.x);
    out[k + 1] = (uint4)(w0.y, w1.y, w2.y, w3.y);
    out[k + 2] = (uint4)(w0.z, w1.z, w2.z, w3.z);
    out[k + 3] = (uint4)(w0.w, w1.w, w2.w, w3.w);
}
