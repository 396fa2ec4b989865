/* indexing.cl: geometric hashing's vote (vmcl/recognize/indexing.py).
 *
 * vote: one work-item per hit, a pair of an ordered pair of image corners (a, b) and an entry of the library's
 * table under the pair's invariant key (the host looks the keys up and lists the hits, so that every
 * work-item does the same work, rather than one per image pair looping over buckets of very different
 * lengths). The entry is a model view's corner pair (A, B). The similarity that takes A to a and B to b is
 * z = (b - a) / (B - A) as a complex number, with x' = z (x - A) + a; the entry votes for (view, rotation,
 * log scale, where the view's centre lands) in the 16 bins nearest its pose, in a hashed accumulator.
 * Each view hashes into its own region of the accumulator (a power of two sized by the host to the view's
 * hypotheses), so a model with many features neither floods another's bins with collisions nor shares its
 * counts. vote_counts histograms each region's counts. In the emit pass each hit whose best bin among its
 * 16 has at least its view's cutoff (the host's choice) writes its hypothesis (the similarity) to a list,
 * once, naming that bin.
 */
#include "vmcl.h"

/* The similarity taking the model pair onto the image pair, and its pose coordinates in bins
 * (continuous): rotation, log scale, and where the view's centre lands. Returns 0 where the scale is out
 * of range. */
inline int pose_coordinates(float4 image, float4 model, float4 frame, float rot_bin, float scale_bin,
                            float pos_bin, float low, float high, float4 *similarity, float4 *coords)
{
    float mx = model.z - model.x, my = model.w - model.y;
    float ix = image.z - image.x, iy = image.w - image.y;
    float norm = mx * mx + my * my;
    if (norm <= 0.0f) return 0;
    float zr = (ix * mx + iy * my) / norm, zi = (iy * mx - ix * my) / norm;
    float scale = sqrt(zr * zr + zi * zi);
    if (!(scale >= low && scale <= high)) return 0;
    float tx = image.x - (zr * model.x - zi * model.y);
    float ty = image.y - (zi * model.x + zr * model.y);
    float cx = zr * frame.x - zi * frame.y + tx, cy = zi * frame.x + zr * frame.y + ty;
    float cell = pos_bin * frame.z * scale;
    *similarity = (float4)(zr, zi, tx, ty);
    *coords = (float4)((atan2(zi, zr) + M_PI_F) / rot_bin, log(scale) / scale_bin, cx / cell, cy / cell);
    return 1;
}

/* The 16 bins around a pose, as addresses in the view's region (its start plus the hash under the region's
 * mask): bin `combo` (0..15, a lane of the vector) takes, per coordinate d, the bin it falls in or (bit d of
 * combo set) the neighbouring bin on its nearer side, so that poses near a bin's edge still meet. Rotation
 * wraps. The 16 hashes are mixed side by side, one vector operation for all. */
inline uint16 combo_bins(float4 coords, int view, int rot_bins, uint start, uint mask)
{
    const uint16 combo = (uint16)(0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u);
    const uint primes[4] = {19349663u, 83492791u, 2654435761u, 40503u};
    float c[4] = {coords.x, coords.y, coords.z, coords.w};
    uint16 h = (uint16)((uint)view * 73856093u);
    for (int d = 0; d < 4; d++) {
        float f = floor(c[d]);
        int home = (int)f, other = c[d] - f >= 0.5f ? home + 1 : home - 1;
        if (d == 0) {
            home = ((home % rot_bins) + rot_bins) % rot_bins;
            other = ((other % rot_bins) + rot_bins) % rot_bins;
        }
        uint16 b = select((uint16)((uint)home), (uint16)((uint)other), ((combo >> (uint)d) & 1u) != 0u);
        h ^= b * primes[d] + 0x9e3779b9u + (h << 6u) + (h >> 2u);
    }
    return (uint16)start + (h & (uint16)mask);
}

/* The first pass: each hit's 16 votes, and its bins and similarity kept for the later passes (a bin of
 * NO_BIN where the pose's scale is out of range: the hit does not vote), with the combos whose vote was
 * its slot's first (bit combo of hit_first), so that the counting pass reads each filled slot once. */
#define NO_BIN 0xFFFFFFFFu

__kernel void vote(__global const int2 *hits, __global const float4 *pair_points, __global const int *entry_view,
                   __global const float4 *entry_points, __global const float4 *frames,
                   __global const uint2 *regions, __global int *votes, __global uint *hit_bins,
                   __global float4 *hit_similarity, __global ushort *hit_first, int hit_count, float rot_bin, int rot_bins, float scale_bin,
                   float pos_bin, float low, float high)
{
    int h = get_global_id(0);
    if (h >= hit_count) return;
    int2 hit = hits[h];  /* (image pair, table entry) */
    int view = entry_view[hit.y];
    float4 similarity, coords;
    if (!pose_coordinates(pair_points[hit.x], entry_points[hit.y], frames[view], rot_bin, scale_bin, pos_bin, low,
                          high, &similarity, &coords)) {
        hit_bins[16 * (size_t)h] = NO_BIN;
        hit_first[h] = 0;
        return;
    }
    uint16 bins = combo_bins(coords, view, rot_bins, regions[view].x, regions[view].y);
    vstore16(bins, h, hit_bins);
    hit_similarity[h] = similarity;
    uint address[16];
    vstore16(bins, 0, address);
    uint first = 0;
    for (int combo = 0; combo < 16; combo++)
        if (atomic_inc(&votes[address[combo]]) == 0) first |= 1u << combo;
    hit_first[h] = (ushort)first;
}

/* The emit pass: each voting hit whose best bin among its 16 (the most votes, the lowest address among
 * equals) has at least its view's cutoff (the host's choice) writes its similarity to the list, once,
 * naming that bin. */
__kernel void vote_emit(__global const int2 *hits, __global const int *entry_view, __global const int *votes,
                        __global const uint *hit_bins, __global const float4 *hit_similarity,
                        __global const int *cutoffs, __global int *count, __global float4 *found,
                        __global int2 *found_info, int hit_count, int capacity)
{
    int h = get_global_id(0);
    if (h >= hit_count || hit_bins[16 * (size_t)h] == NO_BIN) return;
    int view = entry_view[hits[h].y];
    uint address[16];
    vstore16(vload16(h, hit_bins), 0, address);
    int best = -1, most = cutoffs[view] - 1;
    for (int combo = 0; combo < 16; combo++) {
        int b = (int)address[combo];
        int v = votes[b];
        if (v > most || (v == most && best >= 0 && b < best)) {
            most = v;
            best = b;
        }
    }
    if (best >= 0) {
        int at = atomic_inc(count);
        if (at < capacity) {
            found[at] = hit_similarity[h];
            found_info[at] = (int2)(best, view);
        }
    }
}

/* One work-item per hit: the histogram of each region's bins by their votes, each filled slot counted by
 * the hit whose vote was its first (rows[view]: the start and length of the view's row of `counts`;
 * row[v], v = 1 .. length - 1, the last holding length - 1 votes and more). Only the filled slots are
 * read, where a pass over the whole accumulator read its empty slots too. */
__kernel void vote_counts(__global const int2 *hits, __global const int *entry_view, __global const int *votes,
                          __global const uint *hit_bins, __global const ushort *hit_first,
                          __global const int2 *rows, __global int *counts, int hit_count)
{
    int h = get_global_id(0);
    if (h >= hit_count) return;
    uint first = hit_first[h];
    if (!first) return;
    int2 row = rows[entry_view[hits[h].y]];
    uint address[16];
    vstore16(vload16(h, hit_bins), 0, address);
    for (int combo = 0; combo < 16; combo++)
        if ((first >> combo) & 1u) atomic_inc(&counts[row.x + min(votes[address[combo]], row.y - 1)]);
}
