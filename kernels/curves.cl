/* curves.cl: edge pixels linked into curves (vmcl/group/curves.py). Seed section "Saliency, grouping,
 * and segmentation" and "Powerful primitive operations" (distance doubling finds each curve's principal
 * and every pixel's distance along it).
 *
 * Directions: k = 0..7 is the neighbour (DX[k], DY[k]), counter-clockwise on the screen from east:
 * E, NE, N, NW, W, SW, S, SE; the opposite of k is (k + 4) & 7.
 *
 * Links follow mixed adjacency: 4-neighbours always, a diagonal neighbour only where neither of the two
 * pixels that share the corner with it is an edge pixel. On a staircase the diagonal link would make a
 * triangle with the two 4-links, and every pixel of a one-pixel-thin curve would look like a branch.
 */
#include "vmcl.h"

/* Pixels per work-item in the whole-image passes: most pixels are no edge and cost next to nothing, so
 * a work-item per pixel would spend more on itself than on its pixel. */
#define RUN 16

__constant int DX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
__constant int DY[8] = {0, -1, -1, -1, 0, 1, 1, 1};

inline int is_edge(__global const uchar *edges, int x, int y, int W, int H)
{
    return x >= 0 && y >= 0 && x < W && y < H && edges[(size_t)y * W + x] != 0;
}

/* The link bits of edge pixel (x, y): bit k set where its neighbour k is an edge pixel linked to it. */
inline uint links_of(__global const uchar *edges, int x, int y, int W, int H)
{
    uint bits = 0;
    for (int k = 0; k < 8; k++) {
        if (!is_edge(edges, x + DX[k], y + DY[k], W, H)) continue;
        if ((k & 1) && (is_edge(edges, x + DX[k], y, W, H) || is_edge(edges, x, y + DY[k], W, H))) continue;
        bits |= 1u << k;
    }
    return bits;
}

/* links[p]: bit k set where p and its neighbour k are both edge pixels and linked (0 off the edges). */
__kernel void link_pixels(__global const uchar *edges, __global uchar *links, int W, int H)
{
    int x0 = get_global_id(0) * RUN, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    for (int x = x0; x < min(x0 + RUN, W); x++) {
        size_t p = (size_t)y * W + x;
        links[p] = edges[p] ? (uchar)links_of(edges, x, y, W, H) : 0;
    }
}

/* Curve pixels are edge pixels with at most two links; the others (three or more) are branch pixels,
 * where curves meet and split. curve_links keeps the links between curve pixels; branch marks the
 * branch pixels; is_curve (int, for the scan that numbers them) the curve pixels. */
__kernel void split_branches(__global const uchar *edges, __global uchar *curve_links, __global uchar *branch,
                             __global int *is_curve, int W, int H)
{
    int x0 = get_global_id(0) * RUN, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    for (int x = x0; x < min(x0 + RUN, W); x++) {
        size_t p = (size_t)y * W + x;
        uint own = edges[p] ? links_of(edges, x, y, W, H) : 0;
        uint degree = popcount(own);
        uchar kept = 0;
        if (degree <= 2) {
            /* A neighbour's links are found again here rather than read from a pass of their own: only
             * edge pixels of at most two links look, at no more than two neighbours. */
            while (own) {
                int k = 31 - clz(own & -own);
                own &= own - 1;
                if (popcount(links_of(edges, x + DX[k], y + DY[k], W, H)) <= 2) kept |= (uchar)(1 << k);
            }
        }
        curve_links[p] = kept;
        branch[p] = (uchar)(degree >= 3);
        is_curve[p] = edges[p] != 0 && degree <= 2;
    }
}

/* The number of curve pixels, from the exclusive scan that numbers them. */
__kernel void count_curve_pixels(__global const int *index, __global const int *is_curve, __global int *total, long n)
{
    if (get_global_id(0) == 0) total[0] = index[n - 1] + is_curve[n - 1];
}

/* The slot (0 or 1) of direction k among the set bits of a curve pixel's links, in increasing k. */
inline int slot_of(uchar bits, int k)
{
    return (bits & ((1 << k) - 1)) ? 1 : 0;
}

/* The k of a curve pixel's slot s (the s-th set bit), or -1 when it has no such link. */
inline int link_of(uchar bits, int s)
{
    for (int k = 0; k < 8; k++) {
        if (bits & (1 << k)) {
            if (s == 0) return k;
            s--;
        }
    }
    return -1;
}

/* The tour of each curve: node 2i + s stands at curve pixel i (numbered by index), leaving through its
 * link slot s. Through a real link to pixel j it arrives at j and leaves by j's other slot; a slot with
 * no link (an endpoint's second, or both of an isolated pixel's) turns round at i. Every node has one
 * successor and one predecessor, so the nodes form rings: a path of n pixels is one ring of 2n nodes
 * (there and back), a closed curve two rings of n (one per direction).
 * key ranks the nodes for the principal: the turn-round nodes rank above every other, so a path's
 * principal is one of its two ends. */
__kernel void tour(__global const uchar *curve_links, __global const int *is_curve, __global const int *index,
                   __global int *next, __global int *key, __global int *pixel, int W, int H, int N)
{
    int x0 = get_global_id(0) * RUN, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    for (int x = x0; x < min(x0 + RUN, W); x++) {
        size_t p = (size_t)y * W + x;
        if (!is_curve[p]) continue;
        int i = index[p];
        uchar bits = curve_links[p];
        pixel[i] = (int)p;
        for (int s = 0; s < 2; s++) {
            int node = 2 * i + s;
            int k = link_of(bits, s);
            if (k < 0) {
                next[node] = 2 * i + (1 - s);
                key[node] = 2 * N + node;
            } else {
                size_t q = (size_t)(y + DY[k]) * W + (x + DX[k]);
                int arrived = slot_of(curve_links[q], (k + 4) & 7);
                next[node] = 2 * index[q] + (1 - arrived);
                key[node] = node;
            }
        }
    }
}

/* The packed answer the host reads back at once: field f of curve pixel i at out[f * N + i]. */
#define OUT_PIXEL 0
#define OUT_CURVE 1
#define OUT_POSITION 2
#define OUT_CLOSED 3
#define OUT_MAGNITUDE 4
#define OUT_TURN 5
#define OUT_STEP 6
#define OUT_ANGLE 7

/* Each curve pixel's curve (the largest key of its rings: the same for every pixel of a curve), its arc
 * position from the curve's start, and its forward node (the one that walks towards larger positions).
 * A path's two nodes share one ring whose principal is the turn at one end: the node leaving towards the
 * path lies at distance position + 1, the one coming back at 2n - position (0 at the start itself). A
 * closed curve's pixels have one node in each of two rings; the ring of the larger principal sets the
 * direction and the start. */
__kernel void arc_positions(__global const int *top, __global const int *distance, __global const int *pixel,
                            __global const float *magnitude, int has_magnitude, __global int *forward,
                            __global int *out, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int ta = top[2 * i], tb = top[2 * i + 1], da = distance[2 * i], db = distance[2 * i + 1];
    int p = pixel[i], position;
    out[OUT_PIXEL * N + i] = p;
    if (ta == tb) {
        position = (da == 0 || db == 0) ? 0 : min(da, db) - 1;
        out[OUT_CURVE * N + i] = ta;
        out[OUT_CLOSED * N + i] = 0;
        forward[i] = da == position + 1 ? 2 * i : 2 * i + 1;
    } else {
        position = ta > tb ? da : db;
        out[OUT_CURVE * N + i] = max(ta, tb);
        out[OUT_CLOSED * N + i] = 1;
        forward[i] = ta > tb ? 2 * i : 2 * i + 1;
    }
    out[OUT_POSITION * N + i] = position;
    out[OUT_MAGNITUDE * N + i] = has_magnitude ? as_int(magnitude[p]) : as_int(NAN);
}

/* The node after u along the tour, or u itself where the tour turns round (an open curve's end): walks
 * along a curve hold at its ends. */
inline int walk(__global const int *next, int u)
{
    int v = next[u];
    return (v >> 1) == (u >> 1) ? u : v;
}

inline float2 position_of(__global const int *pixel, int node, int W)
{
    int p = pixel[node >> 1];
    return (float2)((float)(p % W), (float)(p / W));
}

/* The tangent direction at each curve pixel: a derivative filter along the arc (weights[t - 1] for the
 * pixels t ahead and, negated, t behind, t = 1..radius; ends held), applied to the positions. */
__kernel void arc_tangents(__global const int *next, __global const int *pixel, __global const int *forward,
                           __constant float *weights, __global float *angle, int radius, int W, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int ahead = forward[i], behind = forward[i] ^ 1;
    float2 tangent = (float2)(0.0f, 0.0f);
    for (int t = 1; t <= radius; t++) {
        ahead = walk(next, ahead);
        behind = walk(next, behind);
        tangent += weights[t - 1] * (position_of(pixel, ahead, W) - position_of(pixel, behind, W));
    }
    angle[i] = atan2(tangent.y, tangent.x);
}

/* The tangent's turning from each curve pixel to the next along the arc (|angle difference| in
 * [0, pi]), and the step's length (1 or sqrt 2; 0 after an open curve's last pixel). */
__kernel void arc_turns(__global const int *next, __global const int *pixel, __global const int *forward,
                        __global const float *angle, __global int *out, int W, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int u = forward[i], v = walk(next, u);
    float turn = 0.0f, step = 0.0f;
    if (v != u) {
        float d = fabs(angle[v >> 1] - angle[i]);
        turn = d > M_PI_F ? 2.0f * M_PI_F - d : d;
        step = length(position_of(pixel, v, W) - position_of(pixel, u, W));
    }
    out[OUT_TURN * N + i] = as_int(turn);
    out[OUT_ANGLE * N + i] = as_int(angle[i]);
    out[OUT_STEP * N + i] = as_int(step);
}

/* The maps before the curves are drawn in: -1 (BRANCH, -2, at branch pixels), no position, no tangent. */
__kernel void clear_maps(__global const uchar *branch, __global int *labels, __global int *position,
                         __global float *tangent, long n)
{
    long p0 = get_global_id(0) * RUN;
    for (long p = p0; p < min(p0 + RUN, n); p++) {
        labels[p] = branch[p] ? -2 : -1;
        position[p] = -1;
        tangent[p] = NAN;
    }
}

/* Each curve pixel's curve index (numbered by the host, which orders the curves), arc position and
 * tangent drawn into the maps. */
__kernel void draw_maps(__global const int *packed, __global const int *ids, __global int *labels,
                        __global int *position, __global float *tangent, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int p = packed[OUT_PIXEL * N + i];
    labels[p] = ids[i];
    position[p] = packed[OUT_POSITION * N + i];
    tangent[p] = as_float(packed[OUT_ANGLE * N + i]);
}
