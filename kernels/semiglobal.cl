/* semiglobal.cl: the census data term and its min-sum aggregation along scanlines (vmcl/early/semiglobal.py).
 *
 * The stereo MRF's energy over disparities d(p) is sum_p C(p, d_p) + sum_{p,q} V(d_p, d_q), with V = 0 for
 * equal neighbours, P1 for a change of one disparity (a slanted surface) and P2 for a jump (a depth
 * discontinuity: the line process's price, lowered where the brightness changes, since the seed couples
 * depth discontinuities to brightness edges). Minimised exactly along one scanline it is a dynamic
 * program: min-sum messages passed from pixel to pixel (aggregate). Passed along 4 or 8 directions and
 * summed, the messages approximate the 2-D minimum (Hirschmueller's semi-global matching).
 *
 * One work-item per cost cell row, per scanline, per pixel, VEC census codes of a row per work-item: the
 * Connection Machine's processors, one per pixel; the scanline kernels give each processor of a line's
 * first pixel the line (on a CPU, a work-item takes LINES neighbouring lines).
 *
 * Layout: the cost and the sum of messages are (H, W, S) with the D = d_max - d_min + 1 disparities of a
 * pixel contiguous (S = D rounded up to whole vectors of LANES), so that a scanline's step reads and
 * writes one short run. S <= MAX_D (a define, the size of the private message arrays).
 */
#include "vmcl.h"

#ifndef MAX_D
#define MAX_D 64
#endif
#ifndef CENSUS_W
#define CENSUS_W 9
#endif
#ifndef CENSUS_H
#define CENSUS_H 7
#endif

/* The census code of every pixel: bit b set when the b-th pixel of its CENSUS_W x CENSUS_H window (row
 * by row, the centre skipped) is darker than the centre by more than `threshold` times the noise's standard
 * deviation (noise[0]): without a margin, the noise of a flat patch would give it a random code,
 * which matches some other random code by chance, where the flat patch should give no evidence at all.
 * Outside the image the window repeats the border pixel, never darker than itself: those bits stay 0. */
__kernel void census(__global const float *image, __global ulong *codes, long W, long H, float threshold,
                     __global const float *noise)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    /* VEC pixels of the row per work-item: each window pixel is one vector step for all of them. */
    VFLOAT centre = clamped_chunk(image + y * W, x0, W) - threshold * noise[0];
#if VEC == 1
    ulong code = 0;
#else
    VCAT(ulong, VEC) code = (VCAT(ulong, VEC))(0);
#endif
    for (int j = -(CENSUS_H / 2); j <= CENSUS_H / 2; j++) {
        __global const float *row = image + clamp(y + j, (long)0, H - 1) * W;
        for (int i = -(CENSUS_W / 2); i <= CENSUS_W / 2; i++) {
            if (i == 0 && j == 0) continue;
#if VEC == 1
            code = (code << 1) | (ulong)(clamped_chunk(row, x0 + i, W) < centre);
#else
            code = (code << 1) | VCAT(convert_ulong, VEC)(-(clamped_chunk(row, x0 + i, W) < centre));
#endif
        }
    }
    ulong t[VEC];
#if VEC == 1
    t[0] = code;
#else
    VCAT(vstore, VEC)(code, 0, t);
#endif
    for (int i = 0; i < VEC && x0 + i < W; i++) codes[y * W + x0 + i] = t[i];
}

/* The census distances at (x, y) of the 16 disparities d_min + k0 .. + 15, whose right pixels
 * x - d_min - k0 - 15 (= first) .. x - d_min - k0 lie on the row: one reversed vector load. */
inline ushort16 hamming16(ulong code, __global const ulong *right_row, long first)
{
    return convert_ushort16(popcount(code ^ vload16(0, right_row + first).sFEDCBA9876543210));
}

/* Whether the 16 disparities from k0 have their right pixels on the row (then `first` is the leftmost). */
inline int chunk_inside(long x, int d_min, int k0, long W, long *first)
{
    *first = x - (d_min + k0) - 15;
    return *first >= 0 && *first + 15 < W;
}

/* The smallest of 16 lanes. */
inline ushort lowest_lane(ushort16 v)
{
    ushort8 a = min(v.lo, v.hi);
    ushort4 b = min(a.lo, a.hi);
    ushort2 c = min(b.lo, b.hi);
    return min(c.x, c.y);
}

#define LANE_INDEX ((ushort16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))

/* The two cameras' brightness difference, from the pixels whose census match is sure (the census is
 * blind to it): each pixel whose best census cost is at most `sure` bits, and whose best cost away from
 * that disparity and its neighbours is at least `margin` bits worse (at least one such disparity must
 * compete), votes for its match's difference (left - right) in the histogram of the pair's mean
 * brightness bin (TONE_BINS equal bins over the two views' joint span). The mean, not the right
 * view's brightness alone: binned by one noisy value, a bin's difference would lean against that
 * value's noise (the darkest bin holds the pixels whose noise made them darker). The difference is
 * counted in steps of TONE_STEP of the span, up to TONE_REACH steps either way (a quarter of the span). */
#define TONE_BINS 32
#define TONE_REACH 128
#define TONE_SPAN_ARGS __global const float *low_left, __global const float *low_right, \
                       __global const float *high_left, __global const float *high_right
#define TONE_LOW fmin(low_left[0], low_right[0])
#define TONE_HIGH fmax(high_left[0], high_right[0])
#define TONE_STEPS (2 * TONE_REACH + 1)
#define TONE_STEP (1.0f / 512.0f)
__kernel void tone_votes(__global const ulong *left, __global const ulong *right, __global const float *left_grey,
                         __global const float *right_grey, __global int *votes, long W, long H, int D, int d_min,
                         int sure, int margin, TONE_SPAN_ARGS)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    float low = TONE_LOW, span = TONE_HIGH - low;
    if (!(span > 0.0f)) return;
    ulong code = left[y * W + x];
    __global const ulong *right_row = right + y * W;
    /* The best (the first of the smallest) and then its competitors, 16 disparities at a time where their
     * right pixels all lie on the row, one by one elsewhere. */
    int best = 255, at = -1;
    long first;
    for (int k0 = 0; k0 < D; k0 += 16) {
        if (k0 + 16 <= D && chunk_inside(x, d_min, k0, W, &first)) {
            ushort16 c = hamming16(code, right_row, first);
            int lowest = lowest_lane(c);
            if (lowest < best) {
                best = lowest;
                at = k0 + lowest_lane(select((ushort16)16, LANE_INDEX, c == (ushort16)lowest));
            }
            continue;
        }
        for (int k = k0; k < min(k0 + 16, D); k++) {
            long xr = x - (d_min + k);
            if (xr < 0 || xr >= W) continue;
            int c = popcount(code ^ right_row[xr]);
            if (c < best) { best = c; at = k; }
        }
    }
    if (at < 0 || best > sure) return;
    int competitors = 0;
    for (int k0 = 0; k0 < D; k0 += 16) {
        if (k0 + 16 <= D && chunk_inside(x, d_min, k0, W, &first)) {
            int16 k = convert_int16(LANE_INDEX) + (k0 - at);
            short16 competes = convert_short16(abs(k) > (uint16)1);
            if (any(competes & (hamming16(code, right_row, first) < (ushort16)(best + margin)))) return;
            for (int j = 0; j < 16; j++) competitors += abs(k0 + j - at) > 1;
            continue;
        }
        for (int k = k0; k < min(k0 + 16, D); k++) {
            long xr = x - (d_min + k);
            if (abs(k - at) <= 1 || xr < 0 || xr >= W) continue;
            if (popcount(code ^ right_row[xr]) < best + margin) return;
            competitors++;
        }
    }
    if (competitors == 0) return;
    /* The match to a fraction of a pixel (the equiangular vertex of the census costs at the best disparity
     * and its two neighbours; whole where a neighbour is outside the range or the image), and the right
     * view read there: at a whole disparity, a pixel on a brightness edge would be compared with its match
     * moved by up to half a pixel across the edge. */
    long xr = x - (d_min + at);
    float shift = 0.0f;
    if (at > 0 && at + 1 < D && xr + 1 < W && xr > 0) {
        int below = popcount(code ^ right[y * W + xr + 1]), above = popcount(code ^ right[y * W + xr - 1]);
        int rise = max(below, above) - best;
        shift = rise > 0 ? (float)(below - above) / (2.0f * (float)rise) : 0.0f;
    }
    float r = right_grey[y * W + xr];
    if (shift != 0.0f)  /* both neighbours are inside the image then */
        r = mix(r, right_grey[y * W + (shift > 0.0f ? xr - 1 : xr + 1)], fabs(shift));
    float l = left_grey[y * W + x];
    int bin = clamp((int)((0.5f * (l + r) - low) / span * TONE_BINS), 0, TONE_BINS - 1);
    float step = (l - r) / (span * TONE_STEP);
    int s = (int)clamp(rint(step), (float)-TONE_REACH, (float)TONE_REACH) + TONE_REACH;
    atomic_inc(votes + bin * TONE_STEPS + s);
}

/* Each brightness bin's offset: the median of its votes (in levels), where it has at least `least` (>= 1);
 * a bin with fewer takes the offset interpolated between the nearest bins that have enough, or the
 * nearest one's beyond the last; 0 everywhere when no bin has enough. One work-item: the bins are few. */
__kernel void tone_offsets(__global const int *votes, __global float *offset, int least, TONE_SPAN_ARGS)
{
    if (get_global_id(0) != 0) return;
    float unit = (TONE_HIGH - TONE_LOW) * TONE_STEP;
    int known[TONE_BINS], count = 0;
    least = max(least, 1);
    for (int b = 0; b < TONE_BINS; b++) {
        __global const int *h = votes + b * TONE_STEPS;
        long total = 0;
        for (int s = 0; s < TONE_STEPS; s++) total += h[s];
        if (total < least) continue;
        long running = 0;
        int s = 0;
        while (2 * (running + h[s]) < total) running += h[s++];
        /* The median read within its step, the step's votes spread evenly over it. */
        float inside = ((float)total / 2.0f - (float)running) / (float)h[s] - 0.5f;
        offset[b] = ((float)(s - TONE_REACH) + inside) * unit;
        known[count++] = b;
    }
    for (int b = 0; b < TONE_BINS; b++) {
        if (count == 0) { offset[b] = 0.0f; continue; }
        int k = 0;
        while (k < count && known[k] < b) k++;
        if (k < count && known[k] == b) continue;
        if (k == 0) offset[b] = offset[known[0]];
        else if (k == count) offset[b] = offset[known[count - 1]];
        else {
            int a = known[k - 1], c = known[k];
            offset[b] = offset[a] + (offset[c] - offset[a]) * (float)(b - a) / (float)(c - a);
        }
    }
}

/* The offset of the pair's mean brightness m, interpolated linearly between bin centres (constant beyond
 * the first and last). */
inline float tone_offset(__global const float *offset, float m, float low, float span)
{
    float place = clamp((m - low) / span * TONE_BINS - 0.5f, 0.0f, TONE_BINS - 1.0f);
    int b = min((int)place, TONE_BINS - 2);
    return mix(offset[b], offset[b + 1], place - (float)b);
}

/* The right view's brightness moved by the offset, so that it reads as the left camera would have seen it.
 * The offsets are indexed by the pair's mean m = v + offset(m) / 2, which one step from m = v finds to
 * within the offsets' change over half an offset. */
__kernel void apply_tone(__global const float *grey, __global float *out, __global const float *offset, long n,
                         TONE_SPAN_ARGS)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float v = grey[i], low = TONE_LOW, span = TONE_HIGH - low;
    if (!(span > 0.0f)) { out[i] = v; return; }
    out[i] = v + tone_offset(offset, v + 0.5f * tone_offset(offset, v, low, span), low, span);
}

/* C(x, y, d) = Hamming distance between the left code at x and the right code at x - d, plus
 * `ad_weight` times the two pixels' absolute brightness difference in units of the noise's standard
 * deviation (noise[0]), capped at `ad_cap` (the pixel's own evidence, which a window straddling a depth
 * edge does not blur; capped so that an outlier, e.g. a specular spot, costs no more than a poor census
 * match). The difference is the mean over the `planes` planes of the levels (grey: one; colour: R, G and
 * B, each W * H, which tell apart surfaces of one grey but different hues). Where x - d falls outside the
 * right image, `outside` (what unrelated pixels cost on average: no evidence for or against d). The host
 * keeps the sum within a uchar. */
__kernel void census_costs(__global const ulong *left, __global const ulong *right, __global const float *left_levels,
                           __global const float *right_levels, int planes, __global uchar *cost, long W, long H,
                           int D, int S, int d_min, uchar outside, float ad_weight, float ad_cap,
                           __global const float *noise)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x, n = W * H;
    ulong code = left[i];
    float unit = 1.0f / (fmax(noise[0], FLT_MIN) * (float)planes);
    __global uchar *out = cost + i * S;
    /* 16 disparities at a time where their right pixels all lie on the row: one (reversed) vector load of
     * the right codes and levels, the same operations lane by lane; one by one elsewhere. */
    long first;
    for (int k0 = 0; k0 < D; k0 += 16) {
        if (k0 + 16 <= D && chunk_inside(x, d_min, k0, W, &first)) {
            float16 sum = 0.0f;
            for (int c = 0; c < planes; c++)
                sum += fabs(left_levels[c * n + i]
                            - vload16(0, right_levels + c * n + y * W + first).sFEDCBA9876543210);
            float16 difference = fmin(sum * unit, ad_cap);
            uint16 total = convert_uint16(hamming16(code, right + y * W, first))
                           + convert_uint16(rint(ad_weight * difference));
            vstore16(convert_uchar16(min(total, (uint16)255u)), 0, out + k0);
            continue;
        }
        for (int k = k0; k < min(k0 + 16, D); k++) {
            long xr = x - (d_min + k);
            if (xr < 0 || xr >= W) { out[k] = outside; continue; }
            float sum = 0.0f;
            for (int c = 0; c < planes; c++) sum += fabs(left_levels[c * n + i] - right_levels[c * n + y * W + xr]);
            float difference = fmin(sum * unit, ad_cap);
            out[k] = (uchar)min(255u, (uint)popcount(code ^ right[y * W + xr]) + (uint)rint(ad_weight * difference));
        }
    }
}

/* The magnitude of the response of Immerkaer's noise mask [1 -2 1; -2 4 -2; 1 -2 1] (the difference of two
 * Laplacians, blind to brightness that changes linearly). On the border, where the mask does not fit,
 * the nearest inner pixel's response (a NaN would poison the maximum the host's histogram spans); 0 for
 * images thinner than the mask. On Gaussian noise of standard deviation s the response is Gaussian with
 * deviation 6 s, so its median magnitude is 0.6745 * 6 s. */
__kernel void noise_response(__global const float *grey, __global float *response, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    if (W < 3 || H < 3) { response[y * W + x] = 0.0f; return; }
    size_t i = clamp(y, (long)1, H - 2) * W + clamp(x, (long)1, W - 2);
    __global const float *up = grey + i - W, *here = grey + i, *down = grey + i + W;
    float r = (up[-1] - 2.0f * up[0] + up[1]) - 2.0f * (here[-1] - 2.0f * here[0] + here[1])
              + (down[-1] - 2.0f * down[0] + down[1]);
    response[y * W + x] = fabs(r);
}

/* Message arithmetic runs on LANES disparities at once (one CPU vector register, or a GPU's 16-wide
 * loads); a pixel's D disparities are stored in a run of S = LANES * ceil(D / LANES), the lanes past D
 * unused. In the messages those lanes hold PAD, which no real lane ever takes up: a real message is at
 * most max C + P2 <= 255 + P2, the host bounding P2 so that the paths' sum of such messages fits 16 bits
 * (paths * (255 + P2) <= 65535: P2 <= 7936 for 8 paths, 16128 for 4), and a candidate through a padded
 * lane is at least PAD + P1 >= lowest + P2 (lowest <= 255), never below the jump's ceiling, so every real
 * value is the one the scalar recursion gives. */
#define LANES 16
#define PAD ((ushort)0x3fff)
#define CHUNKS (MAX_D / LANES)

/* Scanlines per work-item of the message kernel. A step's minimum over the disparities is a chain of
 * dependent operations the next step waits for; the steps of several lines, taken in turn, give the
 * processor independent work while it waits. */
#ifndef LINES
#define LINES 1
#endif

/* The messages along direction (dx, dy) on the scanlines from start[k], k < lines, added into `total`
 * (written when `first`), the lines' steps taken in turn; end[k] receives each line's last pixel.
 * L(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d +- 1) + P1, min_k L(p-r, k) + P2(p)) - min_k L(p-r, k);
 * subtracting the previous minimum keeps L at most max C + P2 <= 255 + P2, so the sums of the directions
 * fit 16 bits (the host checks paths * (255 + P2) <= 65535). P2(p) = max(P1, P2 / (1 + gain |I(p) - I(p-r)|)),
 * gain = edge_gain / s, s the noise's standard deviation: brightness changes are counted in units of the
 * noise, whatever the image's scale. */
inline void walk(__global const uchar *cost, __global const float *grey, __global ushort *total,
                 const long2 *start, long2 *end, int lines, long W, long H, int D, int S, int dx, int dy,
                 ushort p1, float p2, float gain, int first)
{
    int chunks = S / LANES;
    const ushort16 lane = (ushort16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    const ushort16 pad = (ushort16)PAD;
    const ushort16 slope = (ushort16)p1;
    ushort16 unused[CHUNKS];
    for (int c = 0; c < chunks; c++) unused[c] = as_ushort16(lane >= (ushort16)(ushort)max(D - c * LANES, 0));
    /* Each line's previous and current pixel's messages, a chunk of PAD on either side of the `chunks`
     * real ones: a lane's neighbours at d - 1 and d + 1 are then one unaligned load away, which PoCL runs
     * faster than a lane shuffle across two vectors. */
    ushort16 messages[LINES][2][CHUNKS + 2];
    long2 at[LINES];
    ushort lowest[LINES];
    float brightness[LINES];
    int now[LINES], going[LINES];
    for (int k = 0; k < lines; k++) {
        for (int h = 0; h < 2; h++) messages[k][h][0] = messages[k][h][chunks + 1] = pad;
        /* The line's first pixel: its messages are its costs. */
        at[k] = start[k];
        size_t p = at[k].y * W + at[k].x;
        ushort16 lowest_lanes = pad;
        for (int c = 0; c < chunks; c++) {
            ushort16 l = select(convert_ushort16(vload16(0, cost + p * S + c * LANES)), pad, unused[c]);
            messages[k][0][c + 1] = l;
            lowest_lanes = min(lowest_lanes, l);
            __global ushort *out = total + p * S + c * LANES;
            vstore16(first ? l : vload16(0, out) + l, 0, out);
        }
        lowest[k] = lowest_lane(lowest_lanes);
        brightness[k] = grey[p];
        now[k] = 0;
        going[k] = 1;
    }
    for (int left = lines; left > 0;) {
        for (int k = 0; k < lines; k++) {
            if (!going[k]) continue;
            long x = at[k].x + dx, y = at[k].y + dy;
            if (x < 0 || x >= W || y < 0 || y >= H) {
                going[k] = 0;
                left--;
                continue;
            }
            at[k] = (long2)(x, y);
            size_t p = y * W + x;
            float here = grey[p];
            ushort jump = (ushort)max((float)p1, p2 / (1.0f + gain * fabs(here - brightness[k])));
            brightness[k] = here;
            ushort16 ceiling = (ushort16)(ushort)(lowest[k] + jump), floor = (ushort16)lowest[k];
            ushort16 lowest_lanes = pad;
            int was = now[k];
            const __private ushort *previous = (const __private ushort *)messages[k][was];
            for (int c = 0; c < chunks; c++) {
                const __private ushort *here_d = previous + (c + 1) * LANES;
                ushort16 below = vload16(0, here_d - 1), above = vload16(0, here_d + 1);
                ushort16 best = min(min(messages[k][was][c + 1], ceiling), min(below, above) + slope);
                ushort16 costs = select(convert_ushort16(vload16(0, cost + p * S + c * LANES)), pad, unused[c]);
                ushort16 l = costs + best - floor;
                messages[k][1 - was][c + 1] = l;
                lowest_lanes = min(lowest_lanes, l);
                __global ushort *out = total + p * S + c * LANES;
                vstore16(first ? l : vload16(0, out) + l, 0, out);
            }
            now[k] = 1 - was;
            lowest[k] = lowest_lane(lowest_lanes);
        }
    }
    for (int k = 0; k < lines; k++) end[k] = at[k];
}

/* The messages along direction (dx, dy) and then along (-dx, -dy) on LINES neighbouring scanlines per
 * work-item: the way back finds the lines' costs and sums still in the cache (two launches, one per
 * direction, read them from memory twice). Sums are integers, so the order of the directions does not
 * change them.
 *
 * Scanlines: along a row or a column, one per row or column; diagonal, one from each pixel of the entry
 * row and one from each pixel of the entry column but its first (W + H - 1). */
__kernel void aggregate(__global const uchar *cost, __global const float *grey, __global ushort *total,
                        long W, long H, int D, int S, int dx, int dy, ushort p1, float p2, float edge_gain,
                        __global const float *noise, int first)
{
    float gain = edge_gain / fmax(noise[0], FLT_MIN);
    long count = dy == 0 ? H : dx == 0 ? W : W + H - 1;
    long2 start[LINES], end[LINES];
    int lines = 0;
    for (long id = get_global_id(0) * LINES; id < count && lines < LINES; id++, lines++) {
        long x, y;
        if (dy == 0) {
            x = dx > 0 ? 0 : W - 1; y = id;
        } else if (dx == 0) {
            x = id; y = dy > 0 ? 0 : H - 1;
        } else if (id < W) {
            x = id; y = dy > 0 ? 0 : H - 1;
        } else {
            x = dx > 0 ? 0 : W - 1; y = (dy > 0 ? 0 : H - 1) + dy * (id - W + 1);
        }
        start[lines] = (long2)(x, y);
    }
    if (lines == 0) return;
    walk(cost, grey, total, start, end, lines, W, H, D, S, dx, dy, p1, p2, gain, first);
    walk(cost, grey, total, end, start, lines, W, H, D, S, -dx, -dy, p1, p2, gain, 0);
}

/* The left view's winner at each pixel (smallest summed cost; ties: the smaller d), moved to the vertex of
 * the symmetric V through the sums at d - 1, d, d + 1 (`subpixel`: the equiangular fit, for costs that,
 * like Hamming distances, grow linearly away from the match rather than quadratically; a winner at either end of the disparities
 * that compete stays whole), and its integer d for the consistency check. Only the disparities whose right
 * pixel x - d lies inside the image compete; a pixel with none gets NaN and the winner d_min - 1. */
__kernel void select_left(__global const ushort *total, __global const uchar *cost, __global float *disparity,
                          __global int *winner, __global uchar *out_of_range, long W, long H, int D, int S,
                          int d_min, int subpixel, int poor)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    __global const ushort *s = total + (y * W + x) * S;
    /* Disparities with x - d inside [0, W). */
    int k_lo = max(0, (int)(x - (W - 1)) - d_min), k_hi = min(D - 1, (int)x - d_min);
    out_of_range[y * W + x] = 0;
    if (k_lo > k_hi) { disparity[y * W + x] = NAN; winner[y * W + x] = d_min - 1; return; }
    /* 16 disparities a step, those outside [k_lo, k_hi] masked by a sum no real one reaches (the host keeps
     * paths * (255 + P2) <= 65535, and no multiple of 4 is 65535); the first of the smallest, as a scan from
     * k_lo would find it. */
    int best = k_lo;
    ushort lowest = 0xffff;
    for (int k0 = k_lo & ~15; k0 <= k_hi; k0 += 16) {
        int16 k = convert_int16(LANE_INDEX) + k0;
        ushort16 v = select((ushort16)0xffff, vload16(0, s + k0), convert_short16((k >= k_lo) & (k <= k_hi)));
        ushort m = lowest_lane(v);
        if (m < lowest) {
            lowest = m;
            best = k0 + lowest_lane(select((ushort16)16, LANE_INDEX, v == (ushort16)m));
        }
    }
    /* A winner pressed against the image's edge (the last disparity whose right pixel is inside, where
     * the range goes on) is where the cost was cut off, not a minimum: the match lies outside the right
     * image, and the pixel is treated as unmatched (half-occluded by the frame). */
    if ((best == k_hi && k_hi < D - 1) || (best == k_lo && k_lo > 0)) {
        disparity[y * W + x] = NAN;
        winner[y * W + x] = d_min - 1;
        return;
    }
    /* A winner at an end of the range itself, whose own cost is poor (above `poor`),
     * is where the search stopped rather than a match: the seed's sign of an area outside the matcher's
     * disparity range (low scores at the range's limit). Unmatched, and flagged as such. A good match at
     * the end is kept: the range may end right at the true disparity. */
    if (D > 1 && (best == 0 || best == D - 1) && cost[(y * W + x) * S + best] > poor) {
        disparity[y * W + x] = NAN;
        winner[y * W + x] = d_min - 1;
        out_of_range[y * W + x] = 1;
        return;
    }
    float d = (float)(d_min + best);
    if (subpixel && best > k_lo && best < k_hi) {
        float a = s[best - 1], b = s[best], c = s[best + 1];
        float rise = fmax(a, c) - b;
        if (rise > 0.0f) d += clamp((a - c) / (2.0f * rise), -0.5f, 0.5f);
    }
    disparity[y * W + x] = d;
    winner[y * W + x] = d_min + best;
}

/* The right view's winner at each right pixel xr, from the same sums: the d that minimises
 * S(xr + d, y, d) over the d whose left pixel is inside (Hirschmueller: no second aggregation). */
__kernel void select_right(__global const ushort *total, __global int *winner, long W, long H, int D, int S,
                           int d_min)
{
    long xr = get_global_id(0), y = get_global_id(1);
    if (xr >= W || y >= H) return;
    int best = -1;
    uint best_sum = 0xffffffffu;
    for (int k = 0; k < D; k++) {
        long x = xr + d_min + k;
        if (x < 0 || x >= W) continue;
        uint sum = total[(y * W + x) * S + k];
        if (sum < best_sum) { best_sum = sum; best = k; }
    }
    winner[y * W + xr] = best < 0 ? d_min - 1 : d_min + best;
}

/* Left-right consistency: a left winner d at x is kept when the right view's winner at x - d is within
 * `tolerance` of it. Otherwise the pixel loses its disparity and is half-occluded when no disparity of the
 * range would be confirmed by the right view (no right pixel on its row points back to it: what it sees,
 * the right camera does not), mismatched when one would (the right camera sees it; the left winner was
 * wrong). Hirschmueller 2008, section 3.4. fill_occluded then calls mismatched the half-occluded pixels no
 * nearer surface on their right can hide (its `geometry`). */
__kernel void check_views(__global float *disparity, __global const int *left_winner,
                          __global const int *right_winner, __global const uchar *out_of_range,
                          __global uchar *occluded, __global uchar *mismatched, long W, long H, int D, int d_min,
                          int tolerance)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x;
    int d = left_winner[i];
    long xr = x - d;
    occluded[i] = 0;
    mismatched[i] = 0;
    if (out_of_range[i]) return;  /* already unmatched, for its own reason */
    if (d >= d_min && xr >= 0 && xr < W && abs(right_winner[y * W + xr] - d) <= tolerance) return;
    int seen = 0;
    for (int k = 0; k < D && !seen; k++) {
        long r = x - (d_min + k);
        seen = r >= 0 && r < W && right_winner[y * W + r] == d_min + k;
    }
    occluded[i] = !seen;
    mismatched[i] = seen;
    disparity[i] = NAN;
}

/* VEC values row[a .. a + VEC), NaN past the row's ends. */
inline VFLOAT chunk_or_nan(__global const float *row, long a, long W)
{
#if VEC == 1
    return (a >= 0 && a < W) ? row[a] : NAN;
#else
    if (a >= 0 && a + VEC <= W) return VCAT(vload, VEC)(0, row + a);
    float t[VEC];
    for (int i = 0; i < VEC; i++) t[i] = (a + i >= 0 && a + i < W) ? row[a + i] : NAN;
    return VCAT(vload, VEC)(0, t);
#endif
}

/* The median of the kept disparities of each kept pixel's 3 x 3 neighbourhood (itself included; pixels
 * without one stay without): isolated wrong winners, a pixel or two wide, give way to their neighbours'
 * value, while a surface's edge, held by the pixels on its own side, stays where it is. VEC pixels of a
 * row per work-item: the 9 values sorted by a network of min/max steps (odd-even transposition, 9 rounds),
 * missing ones as +infinity at the end, so every step is a vector step. */
__kernel void median_kept(__global const float *disparity, __global float *out, long W, long H)
{
    long x0 = get_global_id(0) * VEC, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    VFLOAT v[9];
    VIT kept = 0;
    for (int k = 0; k < 9; k++) {
        long yy = y + k / 3 - 1;
        VFLOAT d = (yy >= 0 && yy < H) ? chunk_or_nan(disparity + yy * W, x0 + k % 3 - 1, W) : (VFLOAT)NAN;
        kept += select((VIT)1, (VIT)0, isnan(d));
        v[k] = select(d, (VFLOAT)INFINITY, isnan(d));
    }
    for (int round = 0; round < 9; round++)
        for (int k = round & 1; k + 1 < 9; k += 2) {
            VFLOAT low = fmin(v[k], v[k + 1]);
            v[k + 1] = fmax(v[k], v[k + 1]);
            v[k] = low;
        }
    VIT middle = kept >> 1;
    VFLOAT upper = v[0], lower = v[0];
    for (int k = 1; k < 9; k++) {
        upper = select(upper, v[k], middle == k);
        lower = select(lower, v[k], middle - 1 == k);
    }
    VFLOAT centre = chunk_or_nan(disparity + y * W, x0, W);
    VFLOAT found = select(0.5f * (lower + upper), upper, (kept & 1) != 0);
    found = select(found, (VFLOAT)NAN, isnan(centre));
#if VEC == 1
    out[y * W + x0] = found;
#else
    float t[VEC];
    VCAT(vstore, VEC)(found, 0, t);
    for (int i = 0; i < VEC && x0 + i < W; i++) out[y * W + x0 + i] = t[i];
#endif
}

/* Half-occluded pixels take the background's disparity: of the nearest kept disparities to their left
 * and right on the row, the smaller (the farther surface, which the nearer one hides from one view).
 * With `geometry`: the right camera cannot see a pixel of the left view only where a nearer surface on
 * its right hides it, so a pixel no right pixel points back to, between kept pixels whose disparity does
 * not grow by a pixel or more from its left to its right, is mismatched, not half-occluded (a patch the
 * matcher could not match, within one surface or left of a farther one), and stays without a value. An
 * unconfirmed pixel (half-occluded or mismatched) where the surface on its right, carried on to it,
 * would be seen left of the right image's first column (x < that surface's disparity) is hidden by the
 * frame, not by a nearer surface: it is half-occluded, and takes that surface's disparity whatever lies
 * to its left. One work-item per row; `filled` is the disparity with them filled (NaN where a row has no
 * kept pixel); other pixels are copied. */
__kernel void fill_occluded(__global const float *disparity, __global uchar *occluded, __global uchar *mismatched,
                            __global float *filled, long W, long H, int geometry)
{
    long y = get_global_id(0);
    if (y >= H) return;
    __global const float *row = disparity + y * W;
    __global uchar *hidden = occluded + y * W, *wrong = mismatched + y * W;
    __global float *out = filled + y * W;
    /* Left to right: the nearest kept value on the left; then right to left, the smaller of it and the
     * nearest on the right (fmin ignores a NaN: a side with none gives way to the other). */
    float last = NAN;
    for (long x = 0; x < W; x++) {
        if (!isnan(row[x])) last = row[x];
        out[x] = hidden[x] ? last : row[x];
    }
    last = NAN;
    for (long x = W - 1; x >= 0; x--) {
        if (!isnan(row[x])) {
            last = row[x];
        } else if ((hidden[x] || wrong[x]) && (float)x < last) {
            out[x] = last;
            hidden[x] = 1;
            wrong[x] = 0;
        } else if (geometry && hidden[x] && last - out[x] < 1.0f) {
            /* out[x] holds the nearest kept value on the left; a NaN on either side compares false. */
            out[x] = NAN;
            hidden[x] = 0;
            wrong[x] = 1;
        } else if (hidden[x]) {
            out[x] = fmin(out[x], last);
        }
    }
}

/* The pixels the weighted median refines (vmcl/early/weighted_median.py) and those that vote. A census
 * window straddling a depth edge carries the nearer surface's disparity up to half its width over the
 * farther one: every pixel within that band of a jump of `filled` (neighbours differing by more than
 * `jump`, or one without a value beside one with) is refined, as is every mismatched pixel;
 * half-occluded pixels keep their background's value. The kept (confirmed) pixels vote.
 *
 * jump_flags marks each pixel whose right or lower neighbour makes a jump with it; the host sums the
 * marks over the band's window (vmcl.cm.scan.box_sum), and refine_targets reads the sums. */
inline int jumps(float d, float e, float jump)
{
    return isnan(d) != isnan(e) || fabs(d - e) > jump;
}

__kernel void jump_flags(__global const float *filled, __global int *flags, long W, long H, float jump)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x;
    float d = filled[i];
    flags[i] = (x + 1 < W && jumps(d, filled[i + 1], jump)) || (y + 1 < H && jumps(d, filled[i + W], jump));
}

__kernel void refine_targets(__global const float *filled, __global const uchar *occluded,
                             __global const uchar *out_of_range, __global const int *near, __global uchar *where,
                             __global uchar *voters, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = y * W + x;
    voters[i] = !occluded[i] && !isnan(filled[i]);
    /* Out-of-range pixels stay unmatched: their match lies beyond the range, which no neighbour knows. */
    where[i] = !occluded[i] && !out_of_range[i] && (isnan(filled[i]) || near[i] > 0);
}
