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
#include "angles.h"

/* Pixels per work-item in the whole-image passes: most pixels are no edge and cost next to nothing, so
 * a work-item per pixel would spend more on itself than on its pixel. */
#define RUN 16

__constant int DX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
__constant int DY[8] = {0, -1, -1, -1, 0, 1, 1, 1};

inline int is_edge(__global const uchar *edges, int x, int y, int W, int H)
{
    return x >= 0 && y >= 0 && x < W && y < H && edges[(size_t)y * W + x] != 0;
}

/* The links among a pixel's neighbours: bit k of `around` set where neighbour k is an edge pixel; a
 * diagonal one is dropped where either 4-neighbour sharing its corner (k - 1 and k + 1) is an edge pixel. */
inline uint links_among(uint around)
{
    uint four = around & 0x55u;
    uint shared = ((four << 1) | (four >> 1) | ((four & 1u) << 7)) & 0xaau;
    return around & ~shared;
}

/* The link bits of edge pixel (x, y): bit k set where its neighbour k is an edge pixel linked to it. */
inline uint links_of(__global const uchar *edges, int x, int y, int W, int H)
{
    uint around = 0;
    for (int k = 0; k < 8; k++)
        around |= (uint)is_edge(edges, x + DX[k], y + DY[k], W, H) << k;
    return links_among(around);
}

/* Edge bits of row yy (0 outside the image) over the columns x0 - 2 .. x0 + RUN + 1: bit i is column x0 - 2 + i. */
inline uint row_bits(__global const uchar *edges, int x0, int yy, int W, int H)
{
    if (yy < 0 || yy >= H) return 0;
    __global const uchar *row = edges + (size_t)yy * W;
    uint bits = 0;
    int i = 0;
    if (x0 >= 2 && x0 + RUN - 2 <= W) {
        /* The first 16 columns at once: each non-zero byte selects its bit, and the bits are or-ed together. */
        const ushort16 bit = (ushort16)(1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384, 32768);
        ushort16 set = select((ushort16)0, bit, convert_short16(vload16(0, row + x0 - 2)) != (short16)0);
        ushort8 a = set.lo | set.hi;
        ushort4 b = a.lo | a.hi;
        ushort2 c = b.lo | b.hi;
        bits = (uint)(c.x | c.y);
        i = 16;
    }
    for (; i < RUN + 4; i++) {
        int x = x0 - 2 + i;
        if (x >= 0 && x < W && row[x]) bits |= 1u << i;
    }
    return bits;
}

/* The neighbour bits (bit k: neighbour k is an edge pixel) of bit i of the middle of three rows' bits. */
inline uint around_bit(uint up, uint middle, uint down, int i)
{
    return ((middle >> (i + 1)) & 1u) | ((up >> (i + 1)) & 1u) << 1 | ((up >> i) & 1u) << 2
           | ((up >> (i - 1)) & 1u) << 3 | ((middle >> (i - 1)) & 1u) << 4 | ((down >> (i - 1)) & 1u) << 5
           | ((down >> i) & 1u) << 6 | ((down >> (i + 1)) & 1u) << 7;
}

/* The run (RUN pixels of a row, rows one after another) that holds pixel (x, y). */
inline size_t run_of(int x, int y, int W)
{
    return (size_t)y * ((W + RUN - 1) / RUN) + x / RUN;
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
 * where curves meet and split. curve_links keeps the links between curve pixels (written at curve pixels
 * only: nothing reads it elsewhere). Each run's curve pixels are marked in run_bits (bit b: the run's
 * pixel b) and counted in run_count, whose exclusive scan numbers them. The branch pixels' flat
 * addresses are listed, in no particular order (a few in an image; the host sorts them): counts[1]
 * (zeroed before) counts them, and the list has room for every pixel. With `draw`, the maps are cleared
 * as well (labels -1, -2 at branch pixels; no position; no tangent), so the curves can be drawn into
 * them as they are put in order. */
__kernel void split_branches(__global const uchar *edges, __global uchar *curve_links, __global ushort *run_bits,
                             __global int *run_count, __global int *branch_list, __global int *counts,
                             __global int *labels, __global int *position, __global float *tangent, int draw,
                             int W, int H)
{
    int x0 = get_global_id(0) * RUN, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    size_t p0 = (size_t)y * W + x0;
    int end = min(x0 + RUN, W);
    size_t run_index = run_of(x0, y, W);
    run_bits[run_index] = 0;
    run_count[run_index] = 0;
    if (draw) {
        if (end == x0 + RUN) {
            vstore16((int16)(-1), 0, labels + p0);
            vstore16((int16)(-1), 0, position + p0);
            vstore16((float16)(NAN), 0, tangent + p0);
        } else {
            for (size_t p = p0; p < p0 + (size_t)(end - x0); p++) {
                labels[p] = -1;
                position[p] = -1;
                tangent[p] = NAN;
            }
        }
    }
    /* The run's pixels and their neighbours' neighbours, as bits of the five rows around it; most runs
     * hold no edge pixel (Canny marks a few percent of an image) and stay as they were cleared. */
    if (end == x0 + RUN) {
        ulong2 run = as_ulong2(vload16(0, edges + p0));
        if ((run.x | run.y) == 0) return;
    }
    uint rows[5];
    rows[2] = row_bits(edges, x0, y, W, H);
    rows[0] = row_bits(edges, x0, y - 2, W, H);
    rows[1] = row_bits(edges, x0, y - 1, W, H);
    rows[3] = row_bits(edges, x0, y + 1, W, H);
    rows[4] = row_bits(edges, x0, y + 2, W, H);
    /* Only the run's edge pixels (bits 2 .. end - x0 + 1 of the middle row) have links. */
    uint own_edges = rows[2] & (((1u << (end - x0)) - 1u) << 2), curve_bits = 0;
    while (own_edges) {
        int i = 31 - clz(own_edges & -own_edges);
        own_edges &= own_edges - 1;
        size_t p = (size_t)y * W + x0 + i - 2;
        uint own = links_among(around_bit(rows[1], rows[2], rows[3], i));
        uint degree = popcount(own);
        uchar kept = 0;
        if (degree <= 2) {
            /* A neighbour's links are found again here rather than read from a pass of their own: only
             * edge pixels of at most two links look, at no more than two neighbours. */
            while (own) {
                int k = 31 - clz(own & -own);
                own &= own - 1;
                int r = 2 + DY[k];
                if (popcount(links_among(around_bit(rows[r - 1], rows[r], rows[r + 1], i + DX[k]))) <= 2)
                    kept |= (uchar)(1 << k);
            }
        }
        if (degree >= 3) {
            branch_list[atomic_inc(&counts[1])] = (int)p;
            if (draw) labels[p] = -2;
        } else {
            curve_links[p] = kept;
            curve_bits |= 1u << (i - 2);
        }
    }
    run_bits[run_index] = (ushort)curve_bits;
    run_count[run_index] = popcount(curve_bits);
}

/* The number of curve pixels (counts[0]), from the exclusive scan of the runs' counts. */
__kernel void count_curve_pixels(__global const int *run_offset, __global const int *run_count, __global int *counts,
                                 long runs)
{
    if (get_global_id(0) == 0) counts[0] = run_offset[runs - 1] + run_count[runs - 1];
}

/* The number of curve pixel (x, y): its run's offset and the curve pixels before it in the run. */
inline int index_of(__global const ushort *run_bits, __global const int *run_offset, int x, int y, int W)
{
    size_t run_index = run_of(x, y, W);
    return run_offset[run_index] + popcount((uint)run_bits[run_index] & ((1u << (x % RUN)) - 1u));
}

/* The slot (0 or 1) of direction k among the set bits of a curve pixel's links, in increasing k. */
inline int slot_of(uchar bits, int k)
{
    return (bits & ((1 << k) - 1)) ? 1 : 0;
}

/* The k of a curve pixel's slot s (the s-th set bit), or -1 when it has no such link. */
inline int link_of(uchar bits, int s)
{
    uint rest = s ? bits & (bits - 1u) : bits;  /* slot 1: the lowest set bit cleared */
    return rest ? 31 - clz(rest & -rest) : -1;
}

/* The tour of each curve: node 2i + s stands at curve pixel i (numbered by index), leaving through its
 * link slot s. Through a real link to pixel j it arrives at j and leaves by j's other slot; a slot with
 * no link (an endpoint's second, or both of an isolated pixel's) turns round at i. Every node has one
 * successor and one predecessor, so the nodes form rings: a path of n pixels is one ring of 2n nodes
 * (there and back), a closed curve two rings of n (one per direction). Each node's predecessor is
 * written (prev), which is what the doubling walks. key ranks the nodes for the principal: the
 * turn-round nodes rank above every other, so a path's principal is one of its two ends. */
__kernel void tour(__global const uchar *curve_links, __global const ushort *run_bits,
                   __global const int *run_offset, __global int *prev, __global int *key, __global int *pixel,
                   __global int *size_of_key, int W, int H, int N)
{
    int x0 = get_global_id(0) * RUN, y = get_global_id(1);
    if (x0 >= W || y >= H) return;
    size_t run_index = run_of(x0, y, W);
    uint bits = run_bits[run_index];
    int i = run_offset[run_index];
    while (bits) {
        int b = 31 - clz(bits & -bits);
        bits &= bits - 1;
        int x = x0 + b;
        size_t p = (size_t)y * W + x;
        uchar links = curve_links[p];
        pixel[i] = (int)p;
        /* arc_positions gathers at 2N dense keys, two words each: four per curve pixel cleared here. */
        vstore4((int4)0, i, size_of_key);
        for (int s = 0; s < 2; s++) {
            int node = 2 * i + s;
            key[node] = link_of(links, s) < 0 ? 2 * N + node : node;
            /* The node before: the one arriving through the other slot, or this pixel's other node
             * where that slot turns round. */
            int k = link_of(links, 1 - s);
            if (k < 0) {
                prev[node] = 2 * i + (1 - s);
            } else {
                int qx = x + DX[k], qy = y + DY[k];
                int leaving = slot_of(curve_links[(size_t)qy * W + qx], (k + 4) & 7);
                prev[node] = 2 * index_of(run_bits, run_offset, qx, qy, W) + leaving;
            }
        }
        i++;
    }
}

/* The packed answer the host reads back at once, in arc order: field f of the curve pixel in slot j at
 * out[f * N + j], curve after curve (in increasing key), each from its first pixel to its last. */
#define OUT_PIXEL 0
#define OUT_SIZE 1
#define OUT_POSITION 2
#define OUT_CLOSED 3
#define OUT_MAGNITUDE 4
/* The pixels' (column, row) pairs, interleaved over two fields from out[OUT_POINTS * N]: the host takes
 * them as its (N, 2) points without a pass of its own. */
#define OUT_POINTS 5
/* The fields from OUT_TURN on are written after the others, which the host reads (and measures) while
 * the tangents are found. */
#define OUT_TURN 7
#define OUT_STEP 8
#define OUT_ANGLE 9

/* Each curve pixel's curve key (the largest key of its rings: the same for every pixel of a curve), its
 * arc position from the curve's start, and whether its curve is closed. A path's two nodes share one
 * ring whose principal is the turn at one end: the node leaving towards the path lies at distance
 * position + 1, the one coming back at 2n - position (0 at the start itself). A closed curve's pixels
 * have one node in each of two rings; the ring of the larger principal sets the direction and the
 * start. The rings' keys lie in [0, 4N): a node's own number, or 2N + node for a turn; the curve's key
 * is that of its principal made dense, [0, 2N). Each curve's number of pixels, one more than its largest
 * position, is gathered at its key, beside a 1 that counts the curve (size_of_key holds the pairs
 * (size, 1) at 2k and 2k + 1, zeroed by the tour): one scan of the pairs gives each curve its first slot
 * and its number. */
__kernel void arc_positions(__global const int *top, __global const int *distance, __global int *key,
                            __global int *position, __global int *closed, __global int *size_of_key, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int ta = top[2 * i], tb = top[2 * i + 1], da = distance[2 * i], db = distance[2 * i + 1];
    int k, q;
    if (ta == tb) {
        q = (da == 0 || db == 0) ? 0 : min(da, db) - 1;
        k = ta;
        closed[i] = 0;
    } else {
        q = ta > tb ? da : db;
        k = max(ta, tb);
        closed[i] = 1;
    }
    /* The curve's key made dense, in the same order: a node's pixel, after N for a turn. Distinct curves
     * have distinct principals on distinct pixels. */
    k = k < 2 * N ? k / 2 : N + (k - 2 * N) / 2;
    key[i] = k;
    position[i] = q;
    atomic_max(&size_of_key[2 * k], q + 1);
    if (q == 0) size_of_key[2 * k + 1] = 1;  /* one pixel of each curve stands at its start */
}

/* The curve pixels put in arc order: slot = its curve's offset (the exclusive sum of the sizes of the
 * curves of smaller key) + its position. The walks along a curve then read neighbouring slots. With
 * `draw`, the pixel's curve number (the exclusive count of the curves of smaller key) and position go
 * into the maps. */
__kernel void arrange(__global const int *key, __global const int *position, __global const int *closed,
                      __global const int *pixel, __global const float *magnitude, int has_magnitude,
                      __global const int *size_of_key, __global const int *offset_of_key, __global int *out,
                      __global int *labels, __global int *position_map, int draw, int W, int N)
{
    int i = get_global_id(0);
    if (i >= N) return;
    int k = key[i], slot = offset_of_key[2 * k] + position[i], p = pixel[i];
    if (draw) {
        labels[p] = offset_of_key[2 * k + 1];
        position_map[p] = position[i];
    }
    out[OUT_PIXEL * N + slot] = p;
    out[OUT_SIZE * N + slot] = size_of_key[2 * k];
    out[OUT_POSITION * N + slot] = position[i];
    out[OUT_CLOSED * N + slot] = closed[i];
    out[OUT_MAGNITUDE * N + slot] = has_magnitude ? as_int(magnitude[p]) : as_int(NAN);
    /* The walks along the arc read a dozen positions per pixel: dividing each address by the width
     * cost more than the filter itself. */
    vstore2((int2)(p % W, p / W), slot, out + OUT_POINTS * N);
}

/* The slot of arc position q (ahead of or behind the curve's own range) on a curve of `size` pixels
 * starting at slot `start`: round a closed curve, held at an open curve's ends. */
inline int slot_at(int start, int size, int closed, int q)
{
    if (!closed) return start + clamp(q, 0, size - 1);
    /* Within one turn of the loop (every q the filters ask for on all but the tiniest loops) a
     * subtraction or an addition wraps it; the remainder is for the rest. */
    if (q >= size) q = q < 2 * size ? q - size : q % size;
    else if (q < 0) q = q >= -size ? q + size : (q % size + size) % size;
    return start + q;
}

inline float2 position_of(__global const int *out, int j, int N)
{
    return convert_float2(vload2(j, out + OUT_POINTS * N));
}

DEFINE_ATAN2(fast_atan2, float, int)

/* The tangent direction at each curve pixel: a derivative filter along the arc (weights[t - 1] for the
 * pixels t ahead and, negated, t behind, t = 1..radius; ends held), applied to the positions. */
__kernel void arc_tangents(__global int *out, __constant float *weights, int radius, __global float *tangent_map,
                           int draw, int N)
{
    int j = get_global_id(0);
    if (j >= N) return;
    int position = out[OUT_POSITION * N + j], size = out[OUT_SIZE * N + j], closed = out[OUT_CLOSED * N + j];
    int start = j - position;
    float2 tangent = (float2)(0.0f, 0.0f);
    if (position >= radius && position + radius < size) {
        /* Away from the ends (most pixels of long curves) the window is the slots either side. */
        for (int t = 1; t <= radius; t++)
            tangent += weights[t - 1] * (position_of(out, j + t, N) - position_of(out, j - t, N));
    } else {
        for (int t = 1; t <= radius; t++)
            tangent += weights[t - 1] * (position_of(out, slot_at(start, size, closed, position + t), N)
                                         - position_of(out, slot_at(start, size, closed, position - t), N));
    }
    float angle = fast_atan2(tangent.y, tangent.x);
    out[OUT_ANGLE * N + j] = as_int(angle);
    if (draw) tangent_map[out[OUT_PIXEL * N + j]] = angle;
}

/* The tangent's turning from each curve pixel to the next along the arc (|angle difference| in
 * [0, pi]), and the step's length (1 or sqrt 2; 0 after an open curve's last pixel). */
__kernel void arc_turns(__global int *out, int N)
{
    int j = get_global_id(0);
    if (j >= N) return;
    int position = out[OUT_POSITION * N + j];
    int k = slot_at(j - position, out[OUT_SIZE * N + j], out[OUT_CLOSED * N + j], position + 1);
    float turn = 0.0f, step = 0.0f;
    if (k != j) {
        float d = fabs(as_float(out[OUT_ANGLE * N + k]) - as_float(out[OUT_ANGLE * N + j]));
        turn = d > M_PI_F ? 2.0f * M_PI_F - d : d;
        step = length(position_of(out, k, N) - position_of(out, j, N));
    }
    out[OUT_TURN * N + j] = as_int(turn);
    out[OUT_STEP * N + j] = as_int(step);
}
