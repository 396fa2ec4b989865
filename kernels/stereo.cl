/* stereo.cl: the Drumheller-Poggio matcher with the Vision Machine's improvements, seed section "Stereo".
 *
 * One work-item per (x, y, d) cell builds the potential match planes; support is the box sum of each
 * plane (vmcl.cm.scan.box_sum, or the barrier-aware sum below); one work-item per pixel selects the
 * winner. The table variant keeps every plane; the running variant folds each plane into the winner as
 * it is made. Both call consider() in the same order of d, so they give identical results.
 *
 * Defines: FEATURES (0 edges with gradient direction, 1 zero crossings with sign, 2 intensity) and ATTR_T,
 * the type of the feature attribute (float direction or brightness, char sign).
 */
#include "vmcl.h"

#define FEATURES_EDGES 0
#define FEATURES_SIGN 1
#define FEATURES_INTENSITY 2
#ifndef ATTR_T
#define ATTR_T float
#endif

/* p(x, y, d) = 1 where the left feature at (x, y) has a compatible right feature at (x - d, y): gradient
 * directions within `tolerance` radians (edges), or the same sign (zero crossings). For intensity the
 * plane holds the product L(x, y) * R(x - d, y) (0 where x - d is outside), the numerator of the
 * correlation. Planes are float32 so that their box sums (exact below 2^24) feed the score directly. */
__kernel void match_planes(__global const uchar *left, __global const uchar *right,
                           __global const ATTR_T *left_attr, __global const ATTR_T *right_attr,
                           __global float *planes, long W, long H, long D, int d_min, float tolerance)
{
    long x = get_global_id(0), y = get_global_id(1), k = get_global_id(2);
    if (x >= W || y >= H || k >= D) return;
    long xr = x - (d_min + k);
    size_t i = y * W + x, cell = (k * H + y) * W + x;
    int inside = xr >= 0 && xr < W;
#if FEATURES == FEATURES_INTENSITY
    planes[cell] = inside ? left_attr[i] * right_attr[y * W + xr] : 0.0f;
#else
    float p = 0.0f;
    if (inside && left[i] && right[y * W + xr]) {
#if FEATURES == FEATURES_EDGES
        float diff = fabs(left_attr[i] - right_attr[y * W + xr]);
        diff = min(diff, 2.0f * M_PI_F - diff);
        p = diff <= tolerance;
#else
        p = left_attr[i] == right_attr[y * W + xr];
#endif
    }
    planes[cell] = p;
#endif
}

/* The running state of one pixel's selection. */
typedef struct {
    float best_score;   /* best normalised score among planes where the pixel itself matches */
    int best_d;
    float peak;         /* the largest vote count so far */
    float valley;       /* the smallest vote count since that peak */
    float second;       /* the strongest pair of peaks separated by a dip: min of the two peaks */
} Selection;

inline Selection fresh(void)
{
    Selection s = {-INFINITY, INT_MIN, 0.0f, INFINITY, 0.0f};
    return s;
}

/* Folds plane d into the selection: `votes` is the box-summed support, `score` the normalised one, and
 * `own` whether the pixel itself matches on this plane. Ties keep the smaller d (planes come in
 * increasing d). Bimodality is followed as the planes arrive: a later plane and the highest one before
 * it form two peaks when the votes between them dip to `dip` times the lower of the two or less; the
 * strongest such pair is kept (its lower peak, `second`). */
inline void consider(Selection *s, int d, float votes, float score, int own, float dip)
{
    if (own && score > s->best_score) {
        s->best_score = score;
        s->best_d = d;
    }
    if (s->valley <= dip * min(s->peak, votes)) s->second = max(s->second, min(s->peak, votes));
    if (votes > s->peak) {
        s->peak = votes;
        s->valley = INFINITY;
    } else {
        s->valley = min(s->valley, votes);
    }
}

/* The normalised score of cell (x, y, d). Edges: the share of the edges eligible in the two patches
 * that match, v / ((nl + nr) / 2), less `negative` times the unmatched edges as a share of the patch
 * area. Intensity: the normalised cross-correlation of the two patches. */
inline float cell_score(float votes, float nl, float nr, float area, float negative,
                        float sl, float sll, float sr, float srr)
{
#if FEATURES == FEATURES_INTENSITY
    float n = area;
    float cov = votes - sl * sr / n;
    float var = (sll - sl * sl / n) * (srr - sr * sr / n);
    return var > 1e-12f ? cov / sqrt(var) : 0.0f;
#else
    float eligible = 0.5f * (nl + nr);
    if (eligible <= 0.0f) return 0.0f;
    return (votes - negative * (eligible - votes) * eligible / area) / eligible;
#endif
}

/* Per-pixel statistics of the right image at x - d: eligible edges, or the intensity sums. */
#define RIGHT_AT(arr, xr) ((xr) >= 0 && (xr) < W ? (arr)[y * W + (xr)] : 0.0f)

/* Scores cell (x, y, d) from its summed votes and folds it into the pixel's selection; `own` is the
 * cell's own plane value p(x, y, d). */
inline void fold_cell(Selection *s, long x, long y, long W, int d, float votes, float own,
                      __global const float *nl, __global const float *nr, __global const float *sl,
                      __global const float *sll, __global const float *sr, __global const float *srr,
                      float area, float negative, float dip)
{
    long i = y * W + x, xr = x - d;
    float score = cell_score(votes, nl[i], RIGHT_AT(nr, xr), area, negative, sl[i], sll[i], RIGHT_AT(sr, xr),
                             RIGHT_AT(srr, xr));
#if FEATURES == FEATURES_INTENSITY
    consider(s, d, score, score, xr >= 0, dip);
#else
    consider(s, d, votes, score, own > 0.0f, dip);
#endif
}

inline void finish(Selection s, long i, __global float *best_score, __global int *best_d, __global float *peaks)
{
    best_score[i] = s.best_score;
    best_d[i] = s.best_d;
    peaks[3 * i] = s.peak;
    peaks[3 * i + 1] = s.valley;
    peaks[3 * i + 2] = s.second;
}

/* Table variant: one work-item per pixel walks the summed planes of the whole table. */
__kernel void select_table(__global const float *votes, __global const float *planes, __global const uchar *left,
                           __global const float *nl, __global const float *nr,
                           __global const float *sl, __global const float *sll,
                           __global const float *sr, __global const float *srr,
                           __global float *best_score, __global int *best_d, __global float *peaks,
                           long W, long H, long D, int d_min, float area, float negative, float dip)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    Selection s = fresh();
    if (left[i]) {
        for (long k = 0; k < D; k++) {
            size_t cell = (k * H + y) * W + x;
            fold_cell(&s, x, y, W, d_min + (int)k, votes[cell], planes[cell], nl, nr, sl, sll, sr, srr, area,
                      negative, dip);
        }
    }
    finish(s, i, best_score, best_d, peaks);
}

/* Running variant: plane k (already summed) is folded into every pixel's selection; no table. */
__kernel void select_running(__global const float *votes, __global const float *plane, __global const uchar *left,
                             __global const float *nl, __global const float *nr,
                             __global const float *sl, __global const float *sll,
                             __global const float *sr, __global const float *srr,
                             __global float *best_score, __global int *best_d, __global float *peaks,
                             long W, long H, int d, int first, float area, float negative, float dip)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    Selection s = fresh();
    if (!first) {
        s.best_score = best_score[i];
        s.best_d = best_d[i];
        s.peak = peaks[3 * i];
        s.valley = peaks[3 * i + 1];
        s.second = peaks[3 * i + 2];
    }
    if (left[i]) fold_cell(&s, x, y, W, d, votes[i], plane[i], nl, nr, sl, sll, sr, srr, area, negative, dip);
    finish(s, i, best_score, best_d, peaks);
}

/* Uniqueness and ordering, one round from the winners of every pixel: a winner is dropped when another
 * winner on its row claims the same right pixel with a higher score (ties: the smaller x keeps it), or
 * reverses the left-right order with it (the forbidden zone) with a higher score. Flags: out of range
 * where the best score is below `min_score`; discontinuity where the weaker of two dip-separated vote
 * peaks reaches `bimodal` times the highest. */
__kernel void suppress(__global const uchar *left, __global const float *best_score, __global const int *best_d,
                       __global const float *peaks, __global float *disparity, __global float *score,
                       __global uchar *out_of_range, __global uchar *discontinuity,
                       long W, long H, int d_min, int d_max, float min_score, float bimodal, float min_votes)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    float s = best_score[i];
    int d = best_d[i];
    int matched = left[i] && d != INT_MIN;
    int low = matched && s < min_score;
    float peak = peaks[3 * i], second = peaks[3 * i + 2];
    discontinuity[i] = left[i] && peak >= min_votes && second >= bimodal * peak;
    out_of_range[i] = left[i] && (!matched || low);
    int keep = matched && !low;
    long span = d_max - d_min;
    for (long xo = max(0L, x - span); keep && xo <= min(W - 1, x + span); xo++) {
        if (xo == x || !left[y * W + xo]) continue;
        int od = best_d[y * W + xo];
        float os = best_score[y * W + xo];
        if (od == INT_MIN || os < min_score) continue;
        long here = x - d, there = xo - od;
        int stronger = os > s || (os == s && xo < x);
        int same_target = there == here;
        int reversed = (xo - x) * (there - here) < 0;
        if (stronger && (same_target || reversed)) keep = 0;
    }
    disparity[i] = keep ? (float)d : NAN;
    score[i] = matched ? s : NAN;
}

/* Barrier-aware window sums (the support mask): along each line the window of a pixel stops at the
 * barrier-free run holding it. bounds[i] = (first, last) position of pixel i's run along the line
 * (a barrier pixel is a run of its own). Lines: rows (stride 1) or columns (stride W). */
__kernel void run_bounds(__global const uchar *barrier, __global int *first, __global int *last,
                         long W, long H, int along_rows)
{
    long line = get_global_id(0);
    long lines = along_rows ? H : W, n = along_rows ? W : H;
    if (line >= lines) return;
    long base = along_rows ? line * W : line, stride = along_rows ? 1 : W;
    int start = 0;
    for (long t = 0; t < n; t++) {
        int wall = barrier[base + t * stride];
        if (wall || (t > 0 && barrier[base + (t - 1) * stride])) start = (int)t;
        first[base + t * stride] = start;
    }
    int end = (int)n - 1;
    for (long t = n - 1; t >= 0; t--) {
        int wall = barrier[base + t * stride];
        if (wall || (t + 1 < n && barrier[base + (t + 1) * stride])) end = (int)t;
        last[base + t * stride] = end;
    }
}

/* out = prefix[min(t + r, last)] - prefix[max(t - r, first) - 1] along the line, for every plane: the
 * paper's "result of the scan from the processor m in front and m behind", clipped at barriers. */
__kernel void clipped_window(__global const float *prefix, __global const int *first, __global const int *last,
                             __global float *out, long W, long H, long r, int along_rows)
{
    long x = get_global_id(0), y = get_global_id(1), p = get_global_id(2);
    if (x >= W || y >= H) return;
    long i = y * W + x, stride = along_rows ? 1 : W, t = along_rows ? x : y;
    size_t plane = (size_t)p * W * H;
    long hi = min(t + r, (long)last[i]), lo = max(t - r, (long)first[i]);
    long base = i - t * stride;
    float upper = prefix[plane + base + hi * stride];
    float lower = lo > 0 ? prefix[plane + base + (lo - 1) * stride] : 0.0f;
    out[plane + i] = upper - lower;
}

/* Feature masks as float32 counts, and squared brightness, for the patch statistics. */
__kernel void mask_to_float(__global const uchar *mask, __global float *out, long n)
{
    long i = get_global_id(0);
    if (i < n) out[i] = mask[i] ? 1.0f : 0.0f;
}

__kernel void square(__global const float *x, __global float *out, long n)
{
    long i = get_global_id(0);
    if (i < n) out[i] = x[i] * x[i];
}

/* Edges within asin(min_cos)... of horizontal carry no horizontal disparity (the aperture problem along
 * a scanline): they are not features. direction is the gradient's angle, so |cos| measures how far the
 * gradient leans towards x. */
__kernel void drop_horizontal(__global uchar *mask, __global const float *direction, float min_cos, long n)
{
    long i = get_global_id(0);
    if (i < n && mask[i] && fabs(cos(direction[i])) < min_cos) mask[i] = 0;
}
