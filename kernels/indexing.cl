/* indexing.cl: geometric hashing's vote (vmcl/recognize/indexing.py).
 *
 * vote: one work-item per ordered pair of image corners (a, b). Its invariant key (computed on the host) names
 * a bucket of the library's table; each entry there is a model view's corner pair (A, B) with the same
 * key. The similarity that takes A to a and B to b is z = (b - a) / (B - A) as a complex number, with
 * x' = z (x - A) + a; the entry votes for (view, rotation, log scale, where the view's centre lands) in
 * the 16 bins nearest its pose, in a hashed accumulator. Each view hashes into its own region of the
 * accumulator (a power of two sized by the host to the view's hypotheses), so a model with many features
 * neither floods another's bins with collisions nor shares its counts. vote_counts histograms each
 * region's counts. In the emit pass each entry whose best bin among its 16 has at least its view's cutoff
 * (the host's choice) writes its hypothesis (the similarity) to a list, once, naming that bin.
 */
#include "vmcl.h"

inline uint bin_hash(int view, int r, int s, int x, int y)
{
    uint h = (uint)view * 73856093u;
    h ^= (uint)r * 19349663u + 0x9e3779b9u + (h << 6) + (h >> 2);
    h ^= (uint)s * 83492791u + 0x9e3779b9u + (h << 6) + (h >> 2);
    h ^= (uint)x * 2654435761u + 0x9e3779b9u + (h << 6) + (h >> 2);
    h ^= (uint)y * 40503u + 0x9e3779b9u + (h << 6) + (h >> 2);
    return h;
}

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

/* Bin `combo` (0..15) of the 16 around a pose: per coordinate the bin it falls in, or (bit set) the
 * neighbouring bin on its nearer side, so that poses near a bin's edge still meet. Rotation wraps. The
 * address lies in the view's region: its start plus the hash under the region's mask. */
inline uint combo_bin(float4 coords, int combo, int view, int rot_bins, uint start, uint mask)
{
    float c[4] = {coords.x, coords.y, coords.z, coords.w};
    int b[4];
    for (int d = 0; d < 4; d++) {
        float f = floor(c[d]);
        int home = (int)f;
        b[d] = ((combo >> d) & 1) ? (c[d] - f >= 0.5f ? home + 1 : home - 1) : home;
    }
    b[0] = ((b[0] % rot_bins) + rot_bins) % rot_bins;
    return start + (bin_hash(view, b[0], b[1], b[2], b[3]) & mask);
}

__kernel void vote(__global const int *pair_key, __global const float4 *pair_points, __global const int *offsets,
                   __global const int *entry_view, __global const float4 *entry_points, __global const float4 *frames,
                   __global int *votes, __global const uint2 *regions, __global const int *cutoffs,
                   __global int *count, __global float4 *found, __global int2 *found_info, int pairs,
                   float rot_bin, int rot_bins, float scale_bin, float pos_bin, float low, float high, int capacity,
                   int emit)
{
    int p = get_global_id(0);
    if (p >= pairs) return;
    int key = pair_key[p];
    if (key < 0) return;
    float4 image = pair_points[p];
    for (int e = offsets[key]; e < offsets[key + 1]; e++) {
        int view = entry_view[e];
        float4 similarity, coords;
        uint start = regions[view].x, mask = regions[view].y;
        if (!pose_coordinates(image, entry_points[e], frames[view], rot_bin, scale_bin, pos_bin, low, high,
                              &similarity, &coords))
            continue;
        if (!emit) {
            for (int combo = 0; combo < 16; combo++)
                atomic_inc(&votes[combo_bin(coords, combo, view, rot_bins, start, mask)]);
            continue;
        }
        /* Emitted once, to the bin with the most votes among its 16 (the lowest address among equals), if
         * that bin has at least its view's cutoff. */
        int best = -1, most = cutoffs[view] - 1;
        for (int combo = 0; combo < 16; combo++) {
            int h = (int)combo_bin(coords, combo, view, rot_bins, start, mask);
            int v = votes[h];
            if (v > most || (v == most && best >= 0 && h < best)) {
                most = v;
                best = h;
            }
        }
        if (best >= 0) {
            int at = atomic_inc(count);
            if (at < capacity) {
                found[at] = similarity;
                found_info[at] = (int2)(best, view);
            }
        }
    }
}

/* One work-item per accumulator slot: the histogram of each region's bins by their votes (counts[region *
 * bins + v], v = 1 .. bins - 1; the last holds bins - 1 votes and more). Empty slots are not counted.
 * `starts` holds each region's first slot (the regions of the views the lookups met, in order) and,
 * last, the accumulator's size. */
__kernel void vote_counts(__global const int *votes, __global const uint *starts, int views,
                          __global int *counts, int bins)
{
    uint slot = get_global_id(0);
    if (slot >= starts[views]) return;
    int v = votes[slot];
    if (v <= 0) return;
    int low = 0, high = views - 1;  /* the region holding the slot: the last start at or before it */
    while (low < high) {
        int middle = (low + high + 1) / 2;
        if (starts[middle] <= slot) low = middle; else high = middle - 1;
    }
    atomic_inc(&counts[low * bins + min(v, bins - 1)]);
}
