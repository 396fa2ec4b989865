/* stereo.cl: the Drumheller-Poggio matcher with the Vision Machine's improvements, seed section "Stereo".
 *
 * Table variant: one work-item per (x, y, d) cell builds the potential match planes; support is the box
 * sum of each plane (vmcl.cm.scan.box_sum, or the barrier-aware sum below); one work-item per pixel
 * selects the winner over the whole table. Running variant, edges (match_edges): the support of a left
 * feature is summed from the features of its window as it is needed, 16 disparities at a time, and
 * folded into the winner at once; no plane is ever stored. Running variant, intensity: each plane is
 * summed and folded into the winners as it is made. Every path folds the disparities in increasing d
 * with the same rules and the same float expressions, so the variants give identical results. Intensity
 * selections also follow the winner's scores at d - 1 and d + 1 (Around), from which refine_subpixel moves
 * each kept winner to a fraction of a pixel.
 *
 * Feature attributes are 16-bit codes (feature_codes): a gradient direction as a fraction of a turn,
 * 65536 steps (two codes are compatible when their circular distance is at most the tolerance, in the
 * same steps), or a zero crossing's sign (tolerance 0: equal signs). Intensity keeps float brightness.
 *
 * Defines: FEATURES (0 edges with gradient direction, 1 zero crossings with sign, 2 intensity), ATTR_T
 * (ushort codes, float brightness), and for feature_codes SOURCE_T (float direction, char sign).
 */
#include "vmcl.h"

/* Scores are compared across kernels bit for bit: no fused multiply-adds anywhere. */
#pragma OPENCL FP_CONTRACT OFF

#define FEATURES_EDGES 0
#define FEATURES_SIGN 1
#define FEATURES_INTENSITY 2
#ifndef ATTR_T
#define ATTR_T ushort
#endif

/* Two feature codes are compatible when their circular distance (mod 65536) is at most `tolerance`. */
inline int compatible(ushort a, ushort b, int tolerance)
{
    ushort diff = a - b;
    return min(diff, (ushort)(0 - diff)) <= tolerance;
}

/* p(x, y, d) = 1 where the left feature at (x, y) has a compatible right feature at (x - d, y). For
 * intensity the plane holds the product L(x, y) * R(x - d, y) (0 where x - d is outside), the numerator
 * of the correlation. Planes are float32 so that their box sums (exact below 2^24) feed the score
 * directly. */
__kernel void match_planes(__global const uchar *left, __global const uchar *right,
                           __global const ATTR_T *left_attr, __global const ATTR_T *right_attr,
                           __global float *planes, long W, long H, long D, int d_min, int tolerance)
{
    long x = get_global_id(0), y = get_global_id(1), k = get_global_id(2);
    if (x >= W || y >= H || k >= D) return;
    long xr = x - (d_min + k);
    size_t i = y * W + x, cell = (k * H + y) * W + x;
    int inside = xr >= 0 && xr < W;
#if FEATURES == FEATURES_INTENSITY
    planes[cell] = inside ? left_attr[i] * right_attr[y * W + xr] : 0.0f;
#else
    planes[cell] = inside && left[i] && right[y * W + xr]
                   && compatible(left_attr[i], right_attr[y * W + xr], tolerance);
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

/* The winner: the best score among planes where the pixel itself matches (`own`); ties keep the
 * smaller d, since planes come in increasing d. */
inline void choose(Selection *s, int d, float score, int own)
{
    if (own && score > s->best_score) {
        s->best_score = score;
        s->best_d = d;
    }
}

/* Bimodality, followed as the planes arrive: a later plane and the highest one before it form two peaks
 * when the votes between them dip to `dip` times the lower of the two or less; the strongest such pair
 * is kept (its lower peak, `second`). */
inline void follow_peaks(Selection *s, float votes, float dip)
{
    /* Selects, not branches: over a run of planes the outcomes follow the noisy votes, and mispredicted
     * branches cost the running variant more than all its arithmetic. */
    float lower = min(s->peak, votes);
    s->second = s->valley <= dip * lower ? max(s->second, lower) : s->second;
    int rises = votes > s->peak;
    s->valley = rises ? INFINITY : min(s->valley, votes);
    s->peak = rises ? votes : s->peak;
}

/* Folds plane d into the selection: `votes` is the summed support, `score` the normalised one. */
inline void consider(Selection *s, int d, float votes, float score, int own, float dip)
{
    choose(s, d, score, own);
    follow_peaks(s, votes, dip);
}

/* The normalised score of cell (x, y, d). Edges: the share of the edges eligible in the two patches
 * that match, v / ((nl + nr) / 2), less `negative` times the unmatched edges as a share of the patch
 * area. Intensity: the normalised cross-correlation of the two patches, in [-1, 1]; -INFINITY (never
 * chosen) where either patch's variance is too small for float32 to tell from rounding, 1e-5 of its
 * second moment (the images come centred on their means, so that moment is close to the variance
 * wherever the patch is not far brighter or darker than the image). */
inline float cell_score(float votes, float nl, float nr, float area, float negative,
                        float sl, float sll, float sr, float srr)
{
#if FEATURES == FEATURES_INTENSITY
    float n = area;
    float var_l = sll - sl * sl / n, var_r = srr - sr * sr / n;
    if (!(var_l > 1e-5f * sll && var_r > 1e-5f * srr)) return -INFINITY;
    return clamp((votes - sl * sr / n) / sqrt(var_l * var_r), -1.0f, 1.0f);
#else
    float eligible = 0.5f * (nl + nr);
    if (eligible <= 0.0f) return 0.0f;
    return (votes - negative * (eligible - votes) * eligible / area) / eligible;
#endif
}

/* Per-pixel statistics of the right image at x - d (0 outside the image). */
#define RIGHT_AT(arr, xr) ((xr) >= 0 && (xr) < W ? (arr)[y * W + (xr)] : 0.0f)

/* The normalised score of cell (x, y, d) from its summed votes and the patch statistics, a stack of
 * planes: edges (nl, nr), eligible edges in the left and right patches; intensity (sl, sll, sr, srr),
 * the sums of L, L^2, R and R^2. Left planes are read at x, right planes at x - d. */
inline float stats_score(__global const float *stats, long x, long y, long W, long H, int d, float votes,
                         float area, float negative)
{
    long i = y * W + x, xr = x - d, n = W * H;
#if FEATURES == FEATURES_INTENSITY
    return cell_score(votes, 0.0f, 0.0f, area, negative, stats[i], stats[n + i], RIGHT_AT(stats + 2 * n, xr),
                      RIGHT_AT(stats + 3 * n, xr));
#else
    return cell_score(votes, stats[i], RIGHT_AT(stats + n, xr), area, negative, 0.0f, 0.0f, 0.0f, 0.0f);
#endif
}

/* Whether both (2r+1)^2 windows of cell (x, y, d), the left one at x and the right one at x - d, lie inside
 * the image: only then does an intensity score divide the full area's sums. */
inline int windows_inside(long x, long y, long W, long H, int d, long r)
{
    return y >= r && y + r < H && x - r >= 0 && x + r < W && x - d - r >= 0 && x - d + r < W;
}

/* Scores cell (x, y, d) from its summed votes and folds it into the pixel's selection; `own` is the
 * cell's own plane value p(x, y, d). An intensity cell competes only when both of its (2r+1)^2 windows
 * lie inside the image: the score divides by the full area, so a window cut by the border (its sums
 * short of pixels) scored wrongly; at the right border such cells won with d near 0. Returns the
 * intensity cell's score where it competes, else NAN (the sub-pixel neighbours); NAN for edges. */
inline float fold_cell(Selection *s, long x, long y, long W, long H, int d, float votes, float own,
                       __global const float *stats, float area, float negative, float dip, long r)
{
    float score = stats_score(stats, x, y, W, H, d, votes, area, negative);
#if FEATURES == FEATURES_INTENSITY
    int inside = windows_inside(x, y, W, H, d, r);
    consider(s, d, isfinite(score) ? score : 0.0f, score, inside, dip);
    return inside && isfinite(score) ? score : NAN;
#else
    consider(s, d, votes, score, own > 0.0f, dip);
    return NAN;
#endif
}

/* The selection a previous launch stored with finish(), for kernels that fold planes over several launches. */
inline Selection resume(long i, __global const float *best_score, __global const int *best_d,
                        __global const float *peaks)
{
    Selection s = {best_score[i], best_d[i], peaks[3 * i], peaks[3 * i + 1], peaks[3 * i + 2]};
    return s;
}

inline void finish(Selection s, long i, __global float *best_score, __global int *best_d, __global float *peaks)
{
    best_score[i] = s.best_score;
    best_d[i] = s.best_d;
    peaks[3 * i] = s.peak;
    peaks[3 * i + 1] = s.valley;
    peaks[3 * i + 2] = s.second;
}

/* Sub-pixel refinement, intensity only: the winner's neighbouring scores, followed as the planes arrive
 * (d in increasing order, one after the other). `below` and `above` are the scores at best_d - 1 and
 * best_d + 1, `last` the score of the plane folded last; NAN where a cell did not compete (a window
 * outside the image, too flat to score) or no plane exists (the range's ends). Stored as three floats
 * per pixel between launches, like the peaks. */
typedef struct {
    float below, above, last;
} Around;

inline Around no_neighbours(void)
{
    Around a = {NAN, NAN, NAN};
    return a;
}

/* After plane d was folded into `s` with `score` (NAN where the cell did not compete): a winner new at d
 * takes the previous plane's score as its lower neighbour; plane d is the upper neighbour of a winner
 * at d - 1. */
inline void follow_neighbours(Around *a, const Selection *s, int d, float score)
{
    if (s->best_d == d) {
        a->below = a->last;
        a->above = NAN;
    } else if (s->best_d == d - 1) {
        a->above = score;
    }
    a->last = score;
}

inline Around resume_around(long i, __global const float *around)
{
    Around a = {around[3 * i], around[3 * i + 1], around[3 * i + 2]};
    return a;
}

inline void finish_around(Around a, long i, __global float *around)
{
    around[3 * i] = a.below;
    around[3 * i + 1] = a.above;
    around[3 * i + 2] = a.last;
}

/* Table variant: one work-item per pixel walks the summed planes of the whole table. `around` receives
 * the winner's neighbouring scores for intensity; edges leave it untouched (a one-element placeholder).
 * Work-item i takes pixel first_x + i of its row (the rows' tails after select_table_lanes). */
__kernel void select_table(__global const float *votes, __global const float *planes, __global const uchar *left,
                           __global const float *stats, __global float *best_score, __global int *best_d,
                           __global float *peaks, __global float *around,
                           long W, long H, long D, int d_min, float area, float negative, float dip, long r,
                           long first_x)
{
    long x = first_x + get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    Selection s = fresh();
    Around a = no_neighbours();
    if (left[i]) {
        for (long k = 0; k < D; k++) {
            size_t cell = (k * H + y) * W + x;
            int d = d_min + (int)k;
            float score = fold_cell(&s, x, y, W, H, d, votes[cell], planes[cell], stats, area, negative, dip, r);
            follow_neighbours(&a, &s, d, score);
        }
    }
    finish(s, i, best_score, best_d, peaks);
#if FEATURES == FEATURES_INTENSITY
    finish_around(a, i, around);
#endif
}

#if FEATURES == FEATURES_INTENSITY
/* select_table for intensity, sixteen pixels of a row per work-item as float16 lanes (a CPU's SIMD lanes):
 * the same arithmetic in the same order per pixel, with selects for the scalar code's branches, so the
 * fields are bit for bit select_table's. A row's last W % 16 pixels are left to select_table (the host
 * launches it over them, from first_x). */
#define PIXELS 16

/* out[3 i + c] for the sixteen pixels i0 .. i0 + 15, c = 0, 1, 2 taking a, b, c: the interleaved triples
 * (peaks, around) that select_table stores one pixel at a time. */
inline void store_triples(float16 a, float16 b, float16 c, __global float *out, long i0)
{
    float pa[PIXELS], pb[PIXELS], pc[PIXELS];
    vstore16(a, 0, pa);
    vstore16(b, 0, pb);
    vstore16(c, 0, pc);
    for (int j = 0; j < PIXELS; j++) {
        out[3 * (i0 + j)] = pa[j];
        out[3 * (i0 + j) + 1] = pb[j];
        out[3 * (i0 + j) + 2] = pc[j];
    }
}

/* planes and negative are not read (edges only): the kernel takes select_table's arguments as they are. */
__kernel void select_table_lanes(__global const float *votes, __global const float *planes,
                                 __global const uchar *left, __global const float *stats,
                                 __global float *best_score, __global int *best_d, __global float *peaks,
                                 __global float *around, long W, long H, long D, int d_min, float area,
                                 float negative, float dip, long r)
{
    long x0 = get_global_id(0) * PIXELS, y = get_global_id(1);
    if (x0 + PIXELS > W || y >= H) return;
    long n = W * H, i0 = y * W + x0;
    int16 xs = (int)x0 + (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    float16 sl = vload16(0, stats + i0), sll = vload16(0, stats + n + i0);
    __global const float *sr_row = stats + 2 * n + y * W, *srr_row = stats + 3 * n + y * W;
    int rows_inside = y >= r && y + r < H;
    float16 best = (float16)(-INFINITY), peak = (float16)(0.0f), valley = (float16)(INFINITY);
    float16 second = (float16)(0.0f), below = (float16)(NAN), above = (float16)(NAN), last = (float16)(NAN);
    int16 winner = (int16)(INT_MIN);
    for (long k = 0; k < D; k++) {
        int d = d_min + (int)k;
        long xr = x0 - d;
        float16 sr, srr;
        if (xr >= 0 && xr + PIXELS <= W) {
            sr = vload16(0, sr_row + xr);
            srr = vload16(0, srr_row + xr);
        } else {  /* RIGHT_AT: 0 outside the image */
            float a[PIXELS], b[PIXELS];
            for (int j = 0; j < PIXELS; j++) {
                a[j] = RIGHT_AT(stats + 2 * n, xr + j);
                b[j] = RIGHT_AT(stats + 3 * n, xr + j);
            }
            sr = vload16(0, a);
            srr = vload16(0, b);
        }
        float16 v = vload16(0, votes + (k * H + y) * W + x0);
        /* cell_score */
        float16 var_l = sll - sl * sl / area, var_r = srr - sr * sr / area;
        int16 flat = ~((var_l > 1e-5f * sll) & (var_r > 1e-5f * srr));
        float16 score = select(clamp((v - sl * sr / area) / sqrt(var_l * var_r), -1.0f, 1.0f),
                               (float16)(-INFINITY), flat);
        /* windows_inside */
        int16 inside = (int16)(-rows_inside) & (xs - (int)r >= 0) & (xs + (int)r < (int)W)
                       & (xs - d - (int)r >= 0) & (xs - d + (int)r < (int)W);
        int16 finite = isfinite(score);
        /* consider: choose, then follow_peaks with the finite score as the votes */
        int16 take = inside & (score > best);
        best = select(best, score, take);
        winner = select(winner, (int16)d, take);
        float16 counted = select((float16)(0.0f), score, finite);
        float16 lower = min(peak, counted);
        second = select(second, max(second, lower), valley <= dip * lower);
        int16 rises = counted > peak;
        valley = select(min(valley, counted), (float16)(INFINITY), rises);
        peak = select(peak, counted, rises);
        /* follow_neighbours, with fold_cell's return value */
        float16 folded = select((float16)(NAN), score, inside & finite);
        int16 new_winner = winner == d, after_winner = winner == d - 1;
        below = select(below, last, new_winner);
        above = select(select(above, folded, after_winner), (float16)(NAN), new_winner);
        last = folded;
    }
    /* A pixel that is not a left feature keeps a fresh selection (select_table never folds it). */
    int16 feature = convert_int16(vload16(0, left + i0)) != 0;
    best = select((float16)(-INFINITY), best, feature);
    winner = select((int16)(INT_MIN), winner, feature);
    peak = select((float16)(0.0f), peak, feature);
    valley = select((float16)(INFINITY), valley, feature);
    second = select((float16)(0.0f), second, feature);
    below = select((float16)(NAN), below, feature);
    above = select((float16)(NAN), above, feature);
    last = select((float16)(NAN), last, feature);
    vstore16(best, 0, best_score + i0);
    vstore16(winner, 0, best_d + i0);
    store_triples(peak, valley, second, peaks, i0);
    store_triples(below, above, last, around, i0);
}
#endif

/* Running variant for intensity: plane k (already summed) is folded into every pixel's selection;
 * no table. */
__kernel void select_running(__global const float *votes, __global const float *plane, __global const uchar *left,
                             __global const float *stats, __global float *best_score, __global int *best_d,
                             __global float *peaks, __global float *around,
                             long W, long H, int d, int first, float area, float negative, float dip,
                             long r)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    Selection s = first ? fresh() : resume(i, best_score, best_d, peaks);
    Around a = first ? no_neighbours() : resume_around(i, around);
    if (left[i]) {
        float score = fold_cell(&s, x, y, W, H, d, votes[i], plane[i], stats, area, negative, dip, r);
        follow_neighbours(&a, &s, d, score);
    }
    finish(s, i, best_score, best_d, peaks);
    finish_around(a, i, around);
}

/* Shiftable windows, intensity only. The score of cell (x, y, d) as one centred window gives it:
 * -INFINITY where the window leaves the image (either view) or is too flat to score. Its maximum over the
 * (2r+1)^2 centres around each pixel (vmcl.cm.filters.window_max) is the best window that holds the pixel,
 * which select_scores then folds. */
__kernel void intensity_scores(__global const float *votes, __global const float *stats, __global float *scores,
                               long W, long H, long D, int d_min, float area, long r)
{
    long x = get_global_id(0), y = get_global_id(1), k = get_global_id(2);
    if (x >= W || y >= H || k >= D) return;
    int d = d_min + (int)k;
    size_t cell = (k * H + y) * W + x;
    float score = stats_score(stats, x, y, W, H, d, votes[cell], area, 0.0f);
    int inside = windows_inside(x, y, W, H, d, r);
    scores[cell] = inside && isfinite(score) ? score : -INFINITY;
}

/* Folds D planes of finished scores (disparities d_min, d_min + 1, ...) into every pixel's selection,
 * continuing the stored one unless `first`: the table folds all planes in one launch, the running
 * variant one plane per launch. */
__kernel void select_scores(__global const float *scores, __global const uchar *left, __global float *best_score,
                            __global int *best_d, __global float *peaks, __global float *around,
                            long W, long H, long D, int d_min, int first, float dip)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    Selection s = first ? fresh() : resume(i, best_score, best_d, peaks);
    Around a = first ? no_neighbours() : resume_around(i, around);
    if (left[i]) {
        for (long k = 0; k < D; k++) {
            float score = scores[(k * H + y) * W + x];
            int scored = isfinite(score), d = d_min + (int)k;
            consider(&s, d, scored ? score : 0.0f, score, scored, dip);
            follow_neighbours(&a, &s, d, scored ? score : NAN);
        }
    }
    finish(s, i, best_score, best_d, peaks);
    finish_around(a, i, around);
}

/* Sub-pixel disparity of the kept intensity matches: the vertex of the parabola through the winner's
 * scores at d - 1, d, d + 1, d + (s- - s+) / (2 (s- - 2 s + s+)), the offset clamped to [-0.5, 0.5]
 * (within it already, since the winner's score is the largest of the three; the clamp guards rounding).
 * A winner with a missing neighbour (NAN: the range's ends, a cell that did not compete) keeps its
 * integer d, as does a flat triple (a zero denominator). */
__kernel void refine_subpixel(__global float *disparity, __global const float *best_score,
                              __global const float *around, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float d = disparity[i], below = around[3 * i], above = around[3 * i + 1], centre = best_score[i];
    if (isnan(d) || !isfinite(below) || !isfinite(above)) return;
    float curvature = below - 2.0f * centre + above;
    if (!(curvature < 0.0f)) return;
    disparity[i] = d + clamp((below - above) / (2.0f * curvature), -0.5f, 0.5f);
}

/* Uniqueness and ordering, one round from the winners of every pixel: a winner is dropped when another
 * winner on its row claims the same right pixel with a higher score (ties: the smaller x keeps it), or
 * reverses the left-right order with it (the forbidden zone) with a higher score. Flags: out of range
 * where the best score is below `min_score`; discontinuity where the weaker of two dip-separated vote
 * peaks reaches `bimodal` times the highest. One work-item per run of SPAN pixels of a row; each winner
 * looks at its rivals 16 at a time. The winners' fields are read only at left features. */
#define SPAN 16
#define LANE_INDEX(T) ((T)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))

/* Whether any of the 16 pixels from xo0 (features `present`, winners od with scores os) is a stronger
 * winner than (x, d, s) that claims its right pixel or lies in its forbidden zone. */
__attribute__((always_inline)) inline int overruled(int16 present, int16 od, float16 os, int xo0, int x, int d,
                                                    float s, float min_score)
{
    int16 xo = xo0 + LANE_INDEX(int16);
    int16 rival = present && od != INT_MIN && os >= min_score && xo != x;
    int16 there = xo - (rival ? od : 0), here = (int16)(x - d);
    int16 stronger = os > s || (os == s && xo < x);
    int16 reversed = (xo > x && there < here) || (xo < x && there > here);
    return any(rival && stronger && (there == here || reversed));
}

__kernel void suppress(__global const uchar *left, __global const float *best_score, __global const int *best_d,
                       __global const float *peaks, __global float *disparity, __global float *score,
                       __global uchar *out_of_range, __global uchar *discontinuity,
                       long W, long H, int d_min, int d_max, float min_score, float bimodal, float min_votes)
{
    long x_first = get_global_id(0) * SPAN, y = get_global_id(1);
    if (x_first >= W || y >= H) return;
    __global const uchar *row = left + y * W;
    if (x_first + 16 <= W && !any(vload16(0, row + x_first) != (uchar16)0)) {
        long i = y * W + x_first;
        vstore16((float16)NAN, 0, disparity + i);
        vstore16((float16)NAN, 0, score + i);
        vstore16((uchar16)0, 0, out_of_range + i);
        vstore16((uchar16)0, 0, discontinuity + i);
        return;
    }
    for (long x = x_first; x < min(x_first + SPAN, W); x++) {
        long i = y * W + x;
        if (!row[x]) {
            disparity[i] = score[i] = NAN;
            out_of_range[i] = discontinuity[i] = 0;
            continue;
        }
        float s = best_score[i];
        int d = best_d[i];
        int matched = d != INT_MIN;
        int low = matched && s < min_score;
        float peak = peaks[3 * i], second = peaks[3 * i + 2];
        discontinuity[i] = peak >= min_votes && second >= bimodal * peak;
        out_of_range[i] = !matched || low;
        int keep = matched && !low;
        /* A rival at xo with a winner in [d_min, d_max] targets xo - od: to the right it can reach x - d
         * or less only from xo <= x + d_max - d, to the left x - d or more only from xo >= x - d + d_min. */
        long hi = min(W - 1, x + d_max - d);
        for (long xo = max(0L, x - d + d_min); keep && xo <= hi; xo += 16) {
            if (xo + 15 <= hi) {
                uchar16 present = vload16(0, row + xo);
                if (!any(present != (uchar16)0)) continue;
                keep = !overruled(convert_int16(present) != 0, vload16(0, best_d + y * W + xo),
                                  vload16(0, best_score + y * W + xo), (int)xo, (int)x, d, s, min_score);
                continue;
            }
            int present[16] = {0}, od[16] = {0};
            float os[16] = {0.0f};
            for (long k = xo; k <= hi; k++) {
                present[k - xo] = -(row[k] != 0);
                od[k - xo] = best_d[y * W + k];
                os[k - xo] = best_score[y * W + k];
            }
            keep = !overruled(vload16(0, present), vload16(0, od), vload16(0, os), (int)xo, (int)x, d, s, min_score);
        }
        disparity[i] = keep ? (float)d : NAN;
        score[i] = matched ? s : NAN;
    }
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

/* The features both matchers compare, from the feature detector's masks and attributes, for the left
 * and right images at once, 16 pixels per work-item: each feature's 16-bit code (SOURCE_T float: the
 * gradient direction rounded to 1/65536 of a turn; char: the sign), its mask, dropping Canny edges
 * whose gradient lies within `min_angle` codes of vertical, that is edges that close to horizontal (they
 * carry no horizontal disparity: the aperture problem along a scanline), and with WITH_COUNTS the masks
 * again as float32 counts, planes 0 and 1 of `counts`, whose patch sums are the eligible features. */
#define TURN 10430.378350470453f /* 65536 / (2 pi) */
#ifndef SOURCE_T
#define SOURCE_T float
#endif
#define SOURCE16 VCAT(SOURCE_T, 16)

inline void code_lanes(uchar16 mask, SOURCE16 attribute, float min_angle, uchar16 *feature, ushort16 *code,
                       float16 *count)
{
#if SOURCE_T_IS_FLOAT
    ushort16 c = convert_ushort16(convert_int16(rint(attribute * TURN)) & 0xFFFF);
    /* |angle mod pi - pi / 2| in codes: the gradient's distance from vertical. */
    float16 from_vertical = fabs(convert_float16(convert_int16(c & (ushort16)0x7FFF) - 16384));
    int16 keep = convert_int16(mask) != 0 && from_vertical >= min_angle;
#else
    ushort16 c = as_ushort16(convert_short16(attribute));
    int16 keep = convert_int16(mask) != 0;
#endif
    *code = c;
    *feature = convert_uchar16(keep & 1);
    *count = keep ? 1.0f : 0.0f;
}

inline void code_side(__global const uchar *mask, __global const SOURCE_T *attribute, __global uchar *feature,
                      __global ushort *code, __global float *count, float min_angle, long i0, long n)
{
    uchar16 f;
    ushort16 c;
    float16 k;
    if (i0 + 16 <= n) {
        code_lanes(vload16(0, mask + i0), vload16(0, attribute + i0), min_angle, &f, &c, &k);
        vstore16(f, 0, feature + i0);
        vstore16(c, 0, code + i0);
#if WITH_COUNTS
        vstore16(k, 0, count + i0);
#endif
        return;
    }
    uchar m[16] = {0}, fs[16];
    SOURCE_T a[16] = {0};
    ushort cs[16];
    float ks[16];
    for (long i = i0; i < n; i++) {
        m[i - i0] = mask[i];
        a[i - i0] = attribute[i];
    }
    code_lanes(vload16(0, m), vload16(0, a), min_angle, &f, &c, &k);
    vstore16(f, 0, fs);
    vstore16(c, 0, cs);
    vstore16(k, 0, ks);
    for (long i = i0; i < n; i++) {
        feature[i] = fs[i - i0];
        code[i] = cs[i - i0];
#if WITH_COUNTS
        count[i] = ks[i - i0];
#endif
    }
}

__kernel void feature_codes(__global const uchar *left, __global const uchar *right,
                            __global const SOURCE_T *left_attr, __global const SOURCE_T *right_attr,
                            __global uchar *left_features, __global uchar *right_features,
                            __global ushort *left_codes, __global ushort *right_codes, __global float *counts,
                            float min_angle, long n)
{
    long i0 = get_global_id(0) * 16;
    if (i0 >= n) return;
    code_side(left, left_attr, left_features, left_codes, counts, min_angle, i0, n);
    code_side(right, right_attr, right_features, right_codes, counts + n, min_angle, i0, n);
}

/* x -= mean, the mean being sum[0] / n (a device scalar, so the host never waits for it). */
__kernel void subtract_mean(__global float *x, __global const float *sum, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    x[i] -= sum[0] / (float)n;
}

/* The planes whose patch sums the intensity score needs: L, L^2, R and R^2 (plane k at stack + k n). */
__kernel void intensity_moments(__global const float *left, __global const float *right, __global float *stack,
                                long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float l = left[i], r = right[i];
    stack[i] = l;
    stack[n + i] = l * l;
    stack[2 * n + i] = r;
    stack[3 * n + i] = r * r;
}

/* ---- Running variant for edge features: support summed where it is used, no planes ----
 *
 * p(x, y, d) is non-zero only at left features, and only left features are ever selected, so the
 * support of a left feature (x, y) is the sum, over the left features (x', y') of its window, of their
 * potential matches p(x', y', d). Matches are made 16 disparities at a time (a group: short16 lanes,
 * one AVX2 register) and folded into the selection in increasing d. Lane j of a group holds
 * d = top - j, so the right pixels x - d of the 16 lanes are contiguous and ascending. match_edges
 * slides column sums down bands of rows (square windows); match_edges_clipped sums each feature's
 * window directly (windows cut by barriers). */

/* -1 where the left feature at (x, y) with code `a` has a compatible right feature at x - d, for the
 * lanes d = top - j; 0 elsewhere, and for d > d_max or x - d outside the image. */
__attribute__((always_inline)) inline short16 match_lanes(__global const uchar *right,
                                                          __global const ushort *right_code, long row, long W,
                                                          long x, ushort a, int top, int d_max, int tolerance)
{
    long x0 = x - top;
    if (x0 >= 0 && x0 + 15 < W) {
        ushort16 diff = (ushort16)a - vload16(0, right_code + row + x0);
        short16 near = min(diff, (ushort16)0 - diff) <= (ushort16)tolerance;
        short16 present = convert_short16(vload16(0, right + row + x0)) != (short16)0;
        return near & present & (LANE_INDEX(short16) >= (short16)max(top - d_max, 0));
    }
    short lanes[16];
    for (int j = 0; j < 16; j++) {
        long xr = x0 + j;
        lanes[j] = -(top - j <= d_max && xr >= 0 && xr < W && right[row + xr]
                     && compatible(a, right_code[row + xr], tolerance));
    }
    return vload16(0, lanes);
}

/* The 16 lanes d = top - j of a right-image field at row y, x - d (0 outside the image). */
__attribute__((always_inline)) inline float16 right_lanes(__global const float *field, long row, long W, long x,
                                                          int top)
{
    long x0 = x - top;
    if (x0 >= 0 && x0 + 15 < W) return vload16(0, field + row + x0);
    float lanes[16];
    for (int j = 0; j < 16; j++) lanes[j] = x0 + j >= 0 && x0 + j < W ? field[row + x0 + j] : 0.0f;
    return vload16(0, lanes);
}

/* Folds a group without votes on any lane, and says whether it was one: the pixel matches itself on
 * none of its planes (its own match is a vote), and each lane leaves the peaks as they are but the
 * valley, which drops to 0. */
__attribute__((always_inline)) inline int fold_silent(Selection *s, short16 votes)
{
    if (any(votes != (short16)0)) return 0;
    s->valley = 0.0f;
    return 1;
}

/* Folds the 16 lanes d = top - j of a group into the selection, as consider() would one d after the
 * other in increasing d: the best score among the lanes where the pixel matches itself (the first, in
 * d, of equal scores) replaces the running best only when higher; the vote peaks are followed lane by
 * lane (as prefix scans over the lanes, with shuffles, it ran 1.7 times slower on PoCL). The scores
 * are cell_score()'s expression on vectors, which rounds the same. */
__attribute__((always_inline)) inline void fold_lanes(Selection *s, short16 votes, short16 own, float16 eligible,
                                                      int top, int d_max, float area, float negative, float dip)
{
    float16 v = convert_float16(votes);
    float16 score = (v - negative * (eligible - v) * eligible / area) / eligible;
    int16 matches = convert_int16(own) != 0;
    score = eligible <= 0.0f ? 0.0f : score;
    float16 candidates = matches ? score : -INFINITY;
    float8 m8 = fmax(candidates.lo, candidates.hi);
    float4 m4 = fmax(m8.lo, m8.hi);
    float2 m2 = fmax(m4.lo, m4.hi);
    float best = fmax(m2.x, m2.y);
    if (best > s->best_score) {
        int16 at = matches && score == best ? LANE_INDEX(int16) : -1;
        int8 a8 = max(at.lo, at.hi);
        int4 a4 = max(a8.lo, a8.hi);
        int2 a2 = max(a4.lo, a4.hi);
        s->best_score = best;
        s->best_d = top - max(a2.x, a2.y);
    }
    float counts[16];
    vstore16(v, 0, counts);
    Selection peaks = *s;
    for (int j = 15; j >= max(top - d_max, 0); j--) follow_peaks(&peaks, counts[j], dip);
    *s = peaks;
}

/* With barriers: one work-item per run of SPAN pixels of a row visits its features and sums, over each
 * one's window, the matches of the features there, PASS_GROUPS groups per pass over the window. The
 * window of (x, y): rows [y - r, y + r], and on each row y' columns [x - r, x + r], each clipped to the
 * image and to the barrier-free run through (x, y) along the column and through (x, y') along row y'
 * (rows first, then columns: the sums _Support makes for the table). Eligible counts come from `stats`. */
#define PASS_GROUPS 8

__kernel void match_edges_clipped(__global const uchar *left, __global const uchar *right,
                                  __global const ushort *left_code, __global const ushort *right_code,
                                  __global const float *stats, __global const int *row_first,
                                  __global const int *row_last, __global const int *col_first,
                                  __global const int *col_last,
                                  __global float *best_score, __global int *best_d, __global float *peaks,
                                  long W, long H, int d_min, int d_max, long r, int tolerance, float area,
                                  float negative, float dip)
{
    long x_first = get_global_id(0) * SPAN, y = get_global_id(1);
    if (x_first >= W || y >= H) return;
    for (long x = x_first; x < min(x_first + SPAN, W); x++) {
        long i = y * W + x;
        if (!left[i]) continue;
        long y_lo = max(max(y - r, 0L), (long)col_first[i]), y_hi = min(min(y + r, H - 1), (long)col_last[i]);
        Selection s = fresh();
        for (int first = d_min; first <= d_max; first += 16 * PASS_GROUPS) {
            int groups = min(PASS_GROUPS, (d_max - first) / 16 + 1);
            short16 votes[PASS_GROUPS], own[PASS_GROUPS];
            for (int g = 0; g < groups; g++) votes[g] = own[g] = 0;
            for (long yw = y_lo; yw <= y_hi; yw++) {
                long x_lo = max(max(x - r, 0L), (long)row_first[yw * W + x]);
                long x_hi = min(min(x + r, W - 1), (long)row_last[yw * W + x]);
                for (long xw = x_lo; xw <= x_hi; xw++) {
                    if (!left[yw * W + xw]) continue;
                    ushort a = left_code[yw * W + xw];
                    int centre = xw == x && yw == y;
                    for (int g = 0; g < groups; g++) {
                        short16 p = match_lanes(right, right_code, yw * W, W, xw, a, first + 16 * g + 15, d_max,
                                                tolerance);
                        votes[g] -= p;
                        if (centre) own[g] = p;
                    }
                }
            }
            for (int g = 0; g < groups; g++) {
                int top = first + 16 * g + 15;
                if (fold_silent(&s, votes[g])) continue;
                float16 eligible = 0.5f * (stats[i] + right_lanes(stats + W * H, y * W, W, x, top));
                fold_lanes(&s, votes[g], own[g], eligible, top, d_max, area, negative, dip);
            }
        }
        finish(s, i, best_score, best_d, peaks);
    }
}

/* Without barriers the window is a square, and its sum separates: one work-item per band of rows
 * keeps, for every column x and group of 16 disparities, the column sum of p over rows [y - r, y + r]
 * (in `sums`, its own W x groups short16 lanes), adding the features of the row that enters and
 * subtracting those of the row that leaves as y advances (the O(1) box filter), so each feature's
 * matches are computed about twice instead of once per feature of its window. A left feature's
 * support is then the sum of the 2r + 1 column sums around it. The eligible features are counted the
 * same way: column counts of left and right features, summed over the window where a feature needs
 * them (the box sums the other paths read from `stats`, to the bit). */
/* Features are a few per cent of a row: rows are scanned 16 pixels at a time, and a run without any
 * is passed over in one vector compare. `x` runs over the features of row `row` of `mask`. */
#define FOR_FEATURES(mask, row, W, x)                                                      \
    for (long run_ = 0; run_ < (W); run_ += 16)                                            \
        if (run_ + 16 > (W) || any(vload16(0, (mask) + (row) * (W) + run_) != (uchar16)0)) \
            for (long x = run_; x < min(run_ + 16, (W)); x++)                              \
                if ((mask)[(row) * (W) + x])

inline void slide_row(__global short16 *sums, __global const uchar *left, __global const uchar *right,
                      __global const ushort *left_code, __global const ushort *right_code, long W, long yw,
                      int d_min, int d_max, int groups, int tolerance, int entering)
{
    FOR_FEATURES(left, yw, W, x) {
        ushort a = left_code[yw * W + x];
        for (int g = 0; g < groups; g++) {
            short16 p = match_lanes(right, right_code, yw * W, W, x, a, d_min + 16 * g + 15, d_max, tolerance);
            sums[g * W + x] += entering ? -p : p;
        }
    }
}

/* Adds (or takes away) row yw's features to the column counts of one image. */
inline void tally_row(__global int *columns, __global const uchar *features, long W, long yw, int sign)
{
    long x = 0;
    for (; x + 16 <= W; x += 16) {
        int16 counts = convert_int16(vload16(0, features + yw * W + x) != (uchar16)0) & sign;
        vstore16(vload16(0, columns + x) + counts, 0, columns + x);
    }
    for (; x < W; x++) columns[x] += features[yw * W + x] ? sign : 0;
}

/* The window count around x (columns [x - r, x + r] clipped to the image) from the column counts. */
inline int window_count(__global const int *columns, long W, long x, long r)
{
    int count = 0;
    for (long xw = max(x - r, 0L); xw <= min(x + r, W - 1); xw++) count += columns[xw];
    return count;
}

/* The right features' window counts at x - d for the 16 lanes d = top - j (0 outside the image). */
inline float16 right_counts(__global const int *columns, long W, long x, int top, long r)
{
    long x0 = x - top;
    if (x0 - r >= 0 && x0 + 15 + r < W) {
        int16 count = 0;
        for (long k = -r; k <= r; k++) count += vload16(0, columns + x0 + k);
        return convert_float16(count);
    }
    float lanes[16];
    for (int j = 0; j < 16; j++)
        lanes[j] = x0 + j >= 0 && x0 + j < W ? (float)window_count(columns, W, x0 + j, r) : 0.0f;
    return vload16(0, lanes);
}

__kernel void match_edges(__global const uchar *left, __global const uchar *right,
                          __global const ushort *left_code, __global const ushort *right_code,
                          __global short16 *scratch, __global int *tallies,
                          __global float *best_score, __global int *best_d, __global float *peaks,
                          long W, long H, long band, int d_min, int d_max, long r, int tolerance, float area,
                          float negative, float dip)
{
    long b = get_global_id(0), y0 = b * band;
    if (y0 >= H) return;
    int groups = (d_max - d_min) / 16 + 1;
    __global short16 *sums = scratch + b * W * groups;
    __global int *left_columns = tallies + b * 2 * W, *right_columns = left_columns + W;
    for (long k = 0; k < W * groups; k++) sums[k] = 0;
    for (long x = 0; x < W; x++) left_columns[x] = right_columns[x] = 0;
    /* The column sums of the row before the band, rows [y0 - 1 - r, y0 - 1 + r]; each step then adds
     * row y + r and takes away row y - r - 1. */
    for (long yw = max(y0 - r - 1, 0L); yw < min(y0 + r, H); yw++) {
        slide_row(sums, left, right, left_code, right_code, W, yw, d_min, d_max, groups, tolerance, 1);
        tally_row(left_columns, left, W, yw, 1);
        tally_row(right_columns, right, W, yw, 1);
    }
    for (long y = y0; y < min(y0 + band, H); y++) {
        if (y + r < H) {
            slide_row(sums, left, right, left_code, right_code, W, y + r, d_min, d_max, groups, tolerance, 1);
            tally_row(left_columns, left, W, y + r, 1);
            tally_row(right_columns, right, W, y + r, 1);
        }
        if (y - r - 1 >= 0) {
            slide_row(sums, left, right, left_code, right_code, W, y - r - 1, d_min, d_max, groups, tolerance, 0);
            tally_row(left_columns, left, W, y - r - 1, -1);
            tally_row(right_columns, right, W, y - r - 1, -1);
        }
        FOR_FEATURES(left, y, W, x) {
            long i = y * W + x;
            Selection s = fresh();
            float nl = (float)window_count(left_columns, W, x, r);
            for (int g = 0; g < groups; g++) {
                int top = d_min + 16 * g + 15;
                short16 votes = 0;
                for (long xw = max(x - r, 0L); xw <= min(x + r, W - 1); xw++) votes += sums[g * W + xw];
                if (fold_silent(&s, votes)) continue;
                short16 own = match_lanes(right, right_code, y * W, W, x, left_code[i], top, d_max, tolerance);
                fold_lanes(&s, votes, own, 0.5f * (nl + right_counts(right_columns, W, x, top, r)), top, d_max,
                           area, negative, dip);
            }
            finish(s, i, best_score, best_d, peaks);
        }
    }
}
