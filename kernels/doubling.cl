/* doubling.cl: distance doubling (pointer jumping, Wyllie 1979) on linked lists and rings, and
 * connected-component labelling of binary fields. Seed section "Powerful primitive operations"
 * (Distance Doubling) and "Edge detection" (hysteresis "can be reduced to O(log m), using distance
 * doubling").
 *
 * Defines: OP (OP_PLUS or OP_MAX, for jump_step), CONNECTIVITY (4 or 8, for the labelling kernels).
 */
#include "vmcl.h"

/* Every kernel of the file is compiled with each build; defaults let a build for one group of kernels
 * leave the other group's define out. */
#ifndef OP
#define OP OP_PLUS
#endif
#ifndef CONNECTIVITY
#define CONNECTIVITY 8
#endif

/* One doubling step: every node combines its value with that of the node it points to, then points to
 * that node's target, so after step k each node has combined the 2^k nodes ahead of it. A node that
 * points to itself (a list's tail) has the identity (0 for plus) and stays put. */
__kernel void jump_step(__global const int *value, __global const int *pointer,
                        __global int *value_out, __global int *pointer_out, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int p = pointer[i];
#if OP == OP_PLUS
    value_out[i] = value[i] + value[p];
#else
    value_out[i] = max(value[i], value[p]);
#endif
    pointer_out[i] = pointer[p];
}

/* prev[next[i]] = i (next is a permutation on rings); the principal's predecessor link is cut by
 * making the principal point to itself, so ranking along prev measures the distance from it. */
__kernel void reverse_ring(__global const int *next, __global const int *principal,
                           __global int *prev, __global int *rank, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int j = next[i];
    if (principal[j] == j) {
        prev[j] = j;
        rank[j] = 0;
    } else {
        prev[j] = (int)i;
        rank[j] = 1;
    }
}

/* Lists: tails (next = -1) point to themselves with rank 0, every other node has rank 1. */
__kernel void list_init(__global const int *next, __global int *pointer, __global int *rank, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int j = next[i];
    pointer[i] = j < 0 ? (int)i : j;
    rank[i] = j < 0 ? 0 : 1;
}

/* --- connected components ------------------------------------------------------------------------
 * Union-find in which every pointer leads to a larger address: a pixel starts as its own root, and a
 * merge links the smaller root under the larger (compare-and-swap, retried if the root moved). Roots
 * are thus the largest address of their tree, and once all merges are done every component is one
 * tree whose root is its largest address, whatever order the merges ran in: the result is
 * deterministic. Finding a root follows pointers; the final pass jumps every pixel to its root. */

/* Path halving on the way up: each visited pixel is re-pointed at its grandparent, the pointer-jumping
 * step of distance doubling, so repeated finds shorten the trees geometrically. Racing writers only
 * ever store an ancestor, which keeps every pointer valid and leading upward. Defined twice: for labels
 * other work-items may be changing at the same time (volatile), and for a work-item alone in its trees
 * (plain loads and stores, which the compiler may keep in registers). */
#define FIND_ROOT(SUFFIX, QUALIFIER)                                                       \
    inline int find_root##SUFFIX(QUALIFIER int *label, int a)                              \
    {                                                                                      \
        int parent = label[a];                                                             \
        while (parent != a) {                                                              \
            int grandparent = label[parent];                                               \
            if (grandparent != parent) label[a] = grandparent;                             \
            a = parent;                                                                    \
            parent = grandparent;                                                          \
        }                                                                                  \
        return a;                                                                          \
    }

FIND_ROOT(_shared, __global volatile)
FIND_ROOT(_alone, __global)

/* Merges the trees of a and b where other work-items merge too: the smaller root is linked under the
 * larger by compare-and-swap, retried if that root moved meanwhile. */
inline void merge_shared(__global volatile int *label, int a, int b)
{
    for (;;) {
        a = find_root_shared(label, a);
        b = find_root_shared(label, b);
        if (a == b) return;
        if (a < b) { int t = a; a = b; b = t; }
        if (atomic_cmpxchg(&label[b], b, a) == b) return;
    }
}

/* Links two roots of a work-item's own trees, the smaller under the larger; returns the union's root. */
inline int link_alone(__global int *label, int a, int b)
{
    if (a == b) return a;
    int high = max(a, b);
    label[min(a, b)] = high;
    return high;
}

/* Which runs of the row below pixel i = (x, y) must merge with its run (bit 0: below-left, bit 1:
 * below, bit 2: below-right). Runs are already trees, so only the pixels where the set of touching
 * lower runs changes need to merge: a run's first pixel with each lower neighbour that starts a new
 * lower run, the pixels after it only where a new lower run begins below-right (8-connectivity) or
 * directly below (4-connectivity). Computed without branches (most pixels need nothing, and a noisy
 * mask would mispredict a branch on every pixel); any non-zero mask value is foreground. */
inline int merge_targets(__global const uchar *mask, long x, long i, long W)
{
    long below = i + W;
    int here = mask[i] != 0, down = mask[below] != 0;
    int left = x > 0 && mask[i - 1], down_left = x > 0 && mask[below - 1];
#if CONNECTIVITY == 8
    int down_right = x + 1 < W && mask[below + 1];
    int targets = (!left & down_left) | ((!left & down & !down_left) << 1) | ((down_right & !down) << 2);
#else
    int targets = (down & !(left & down_left)) << 1;
#endif
    return here ? targets : 0;
}

/* Work-item s labels the strip of rows [s*rows, (s+1)*rows) on its own, from its bottom row up: per row,
 * every foreground pixel first points at the right end of its horizontal run (the run's largest address,
 * so its root; right to left), then the row's runs merge with those below them. Going up means a new
 * row's roots (smaller addresses) hang under the existing larger roots, which keeps the trees shallow;
 * strips keep the memory walk sequential. Strip borders are merged by label_merge_strips. */
__kernel void label_strips(__global const uchar *mask, __global int *label, long W, long H, long rows)
{
    long y0 = get_global_id(0) * rows;
    if (y0 >= H) return;
    for (long y = min(y0 + rows, H) - 1; y >= y0; y--) {
        int end = -1;
        for (long x = W - 1; x >= 0; x--) {
            int i = (int)(y * W + x);
            end = mask[i] ? (end < 0 ? i : end) : -1;
            label[i] = end;
        }
        if (y + 1 < min(y0 + rows, H)) {
            /* cur: the root of the run being walked, found at its first merge and kept up to date by
             * the merges themselves (the strip is this work-item's alone), so each merge costs one find
             * (the row below's) instead of two. */
            int cur = -1;
            for (long x = 0; x < W; x++) {
                long i = y * W + x;
                int targets = merge_targets(mask, x, i, W);
                cur = mask[i] ? cur : -1;
                if (targets) {
                    if (cur < 0) cur = find_root_alone(label, (int)i);
                    int below = (int)(i + W);
                    if (targets & 1) cur = link_alone(label, cur, find_root_alone(label, below - 1));
                    if (targets & 2) cur = link_alone(label, cur, find_root_alone(label, below));
                    if (targets & 4) cur = link_alone(label, cur, find_root_alone(label, below + 1));
                }
            }
        }
    }
}

/* The last row of every strip but the last merges with the first row of the strip below. */
__kernel void label_merge_strips(__global const uchar *mask, __global volatile int *label, long W, long H,
                                 long rows)
{
    long x = get_global_id(0), y = (get_global_id(1) + 1) * rows - 1;
    if (x >= W || y + 1 >= H) return;
    long i = y * W + x;
    int targets = merge_targets(mask, x, i, W);
    for (int t = 0; t < 3; t++) {
        if (targets & (1 << t)) merge_shared(label, (int)i, (int)(i + W + t - 1));
    }
}

/* Every pixel jumps to its root. One work-item per row: the pixels of a run share a pointer, so the root
 * found for one serves the rest of the run. Other rows' work-items may re-point pixels of this row's
 * trees meanwhile, but only ever at an ancestor, so plain (non-volatile) accesses stay correct. */
__kernel void label_flatten(__global int *label, long W, long H)
{
    long y = get_global_id(0);
    if (y >= H) return;
    int previous = -1, root = -1;
    for (long i = y * W; i < (y + 1) * W; i++) {
        int own = label[i];
        if (own >= 0 && own != previous) {
            previous = own;
            root = find_root_alone(label, own);
            /* Point the whole path at the root, so later finds in this tree take one step. */
            for (int k = own; k != root;) {
                int up = label[k];
                label[k] = root;
                k = up;
            }
        }
        label[i] = own < 0 ? own : root;
    }
}

__kernel void label_init(__global const uchar *mask, __global int *label, long n)
{
    long i = get_global_id(0);
    if (i < n) label[i] = mask[i] ? (int)i : -1;
}

/* One synchronous step of spreading activation (the O(m) variant): every foreground pixel takes the
 * largest label among itself and its foreground neighbours; `changed` is set when any label grew. */
__kernel void propagate_step(__global const int *label, __global int *label_out, __global int *changed,
                             long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    long i = y * W + x;
    int own = label[i];
    if (own < 0) {
        label_out[i] = own;
        return;
    }
    int best = own;
    for (int dy = -1; dy <= 1; dy++) {
        for (int dx = -1; dx <= 1; dx++) {
            if ((CONNECTIVITY == 4 && dx != 0 && dy != 0) || (dx == 0 && dy == 0)) continue;
            long nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
            best = max(best, label[ny * W + nx]);
        }
    }
    label_out[i] = best;
    if (best != own) *changed = 1;
}

/* roots[i] = 1 where pixel i is the root (the largest address) of its component. */
__kernel void mark_roots(__global const int *label, __global int *roots, long n)
{
    long i = get_global_id(0);
    if (i < n) roots[i] = label[i] == (int)i;
}

/* Labels 1..k in order of the roots' addresses, 0 for background; ids is the exclusive scan of roots. */
__kernel void relabel(__global const int *label, __global const int *ids, __global int *out, long n)
{
    long i = get_global_id(0);
    if (i < n) out[i] = label[i] < 0 ? 0 : ids[label[i]] + 1;
}
