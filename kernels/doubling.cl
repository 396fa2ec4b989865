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

/* prev[next[i]] = i: the rings walked backwards. */
__kernel void ring_init(__global const int *next, __global int *prev, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    prev[next[i]] = (int)i;
}

/* Doubling steps backwards along a ring. Before a step, node i knows the largest key among itself and
 * the span - 1 nodes behind it, and how far behind it lies; the node span behind knows the same of the
 * span nodes before those. The larger wins, the nearer on a tie (the same node met again round a short
 * ring), so once span reaches the ring's length every node holds its ring's principal and its distance
 * from it (going forwards from the principal to i is going backwards from i to it). */
inline void take_larger(int *top, int *distance, int their_top, int their_distance, int span)
{
    if (their_top > *top) {
        *top = their_top;
        *distance = their_distance + span;
    }
}

/* `steps` doubling steps in one launch: node i folds in the windows of the 2^steps - 1 nodes span,
 * 2 span, ... behind it, nearest first. A strict "larger" keeps the nearer of equal keys in any order of
 * folding, so this is exactly what `steps` launches of one step would give; each launch costs more than
 * its arithmetic, and a few more dependent reads per node cost less than the launches they save. The
 * first launch (`first` 1) starts every node as its own window's largest key (top holds the keys) at
 * distance 0, and reads no distances. Both are arguments, not defines, so one build serves every step
 * (a kernel object per step keeps them set: Machine.kernel_instance). */
__kernel void principal_steps(__global const int *top, __global const int *distance, __global const int *prev,
                              __global int *top_out, __global int *distance_out, __global int *prev_out,
                              int span, int steps, int first, long n)
{
    long i = get_global_id(0);
    if (i >= n) return;
    int windows = 1 << steps;
    int best = top[i], behind = first ? 0 : distance[i], p = prev[i];
    for (int w = 1; w < windows; w++) {
        take_larger(&best, &behind, top[p], first ? 0 : distance[p], w * span);
        p = prev[p];
    }
    top_out[i] = best;
    distance_out[i] = behind;
    prev_out[i] = p;
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
 * Union-find over runs: maximal horizontal stretches of foreground within a row. Row y's runs take the
 * run indices y * slots, y * slots + 1, ... in order along the row, so run indices follow raster order
 * and the run holding a component's largest flat address is its run of largest index. Every pointer
 * leads to a larger run index: a run starts as its own root, and a merge links the smaller root under
 * the larger. Roots are thus the largest run of their tree, and once all merges are done every
 * component is one tree whose root is its last run in raster order, whatever order the merges ran in:
 * the result is deterministic. Runs rather than pixels, because a run's pixels are connected without
 * any merge: a random 50% field has a quarter as many runs as pixels, and a strip's trees fit in cache.
 * Finding a root follows pointers; the final pass gives every pixel its run's root's last address.
 *
 * bounds[2r] is the flat address of run r's first pixel, bounds[2r + 1] one past its last pixel. */

/* Path halving on the way up: each visited run is re-pointed at its grandparent, the pointer-jumping
 * step of distance doubling, so repeated finds shorten the trees geometrically. Racing writers only
 * ever store an ancestor, which keeps every pointer valid and leading upward. Defined twice: for trees
 * other work-items may be changing at the same time (volatile), and for a work-item alone in its trees
 * (plain loads and stores, which the compiler may keep in registers). */
#define FIND_ROOT(SUFFIX, QUALIFIER)                                                       \
    inline int find_root##SUFFIX(QUALIFIER int *parent, int a)                             \
    {                                                                                      \
        int up = parent[a];                                                                \
        while (up != a) {                                                                  \
            int grandparent = parent[up];                                                  \
            if (grandparent != up) parent[a] = grandparent;                                \
            a = up;                                                                        \
            up = grandparent;                                                              \
        }                                                                                  \
        return a;                                                                          \
    }

FIND_ROOT(_shared, __global volatile)
FIND_ROOT(_alone, __global)

/* Merges the trees of a and b where other work-items merge too: the smaller root is linked under the
 * larger by compare-and-swap, retried if that root moved meanwhile. */
inline void merge_shared(__global volatile int *parent, int a, int b)
{
    for (;;) {
        a = find_root_shared(parent, a);
        b = find_root_shared(parent, b);
        if (a == b) return;
        if (a < b) { int t = a; a = b; b = t; }
        if (atomic_cmpxchg(&parent[b], b, a) == b) return;
    }
}

/* Writes the bounds of row y's runs from run `first` on and returns their number. Without branches (a
 * noisy mask would mispredict one at most pixels): every pixel stores its address at the next free
 * bound, and the count of bounds moves on only where the mask changes, so only those addresses stay.
 * The store after the last bound lands on a spare int, hence slots = W / 2 + 1 runs per row. */
inline int find_runs(__global const uchar *mask, __global int *bounds, long y, long W, int first)
{
    __global int *row_bounds = bounds + 2 * (long)first;
    int row = (int)(y * W), changes = 0, previous = 0;
    for (int x = 0; x < W; x++) {
        int here = mask[row + x] != 0;
        row_bounds[changes] = row + x;
        changes += here ^ previous;
        previous = here;
    }
    row_bounds[changes] = row + (int)W;  /* the end of a run that reaches the row's end */
    return (changes + previous) / 2;
}

/* Runs of rows y and y + 1 touch where they share a column, or with 8-connectivity a corner. The
 * kernels that merge two rows walk both rows' runs together, like merging two sorted lists: at each
 * step the upper run a and the lower run b merge if they touch, then whichever ends first is done, as it
 * cannot touch the other row's next run (both, when they end together). So every touching pair meets
 * once, in at most as many steps as the two rows have runs. */
#define DIAGONAL (CONNECTIVITY == 8)

typedef struct {
    bool touch, a_done, b_done;  /* whether a and b touch; whether the walk leaves a, b behind */
} RunPair;

inline RunPair compare_runs(__global const int *bounds, int a, int b, int W)
{
    int start_a = bounds[2 * (long)a], end_a = bounds[2 * (long)a + 1];
    int start_b = bounds[2 * (long)b] - W, end_b = bounds[2 * (long)b + 1] - W;  /* moved up a row */
    RunPair pair = {start_b < end_a + DIAGONAL && end_b + DIAGONAL > start_a, end_a <= end_b, end_b <= end_a};
    return pair;
}

/* The root of a run in trees that are this work-item's alone, re-pointing the run at it. In the strips'
 * trees nearly every run is at most two steps below its root, so two dependent loads find it without a
 * branch that could mispredict, and only the rare deeper run takes the loop. */
inline int find_root_shallow(__global int *parent, int a)
{
    int up = parent[parent[a]];
    if (parent[up] != up) up = find_root_alone(parent, up);
    parent[a] = up;
    return up;
}

/* Work-item s labels the strip of rows [s*rows, (s+1)*rows) on its own, from its bottom row up: per row,
 * the runs are found, then merged with the touching runs of the row below. Going up means a new row's
 * runs (smaller indices) hang under the existing larger roots, which keeps the trees shallow. The walk
 * carries the roots of its current upper and lower run, so a run touching several others is looked up
 * once, and no branch follows the noisy data: a pair that does not touch points the larger root at
 * itself instead of linking, the upper run's pointer is stored at every step (the last store, its
 * final root, wins), and the lower run's root is looked up at every step, moved on or not. Strip
 * borders are merged by label_merge_strips. */
__kernel void label_strips(__global const uchar *mask, __global int *bounds, __global int *counts,
                           __global int *parent, long W, long H, long rows, long slots)
{
    long y0 = get_global_id(0) * rows;
    if (y0 >= H) return;
    int lower_count = 0;  /* the strip's bottom row has no runs below it in the strip */
    for (long y = min(y0 + rows, H) - 1; y >= y0; y--) {
        int first = (int)(y * slots), count = find_runs(mask, bounds, y, W, first);
        counts[y] = count;
        int a = first, a_end = first + count, b = first + (int)slots, b_end = b + lower_count;
        int root_a = a, root_b = b < b_end ? find_root_shallow(parent, b) : -1;
        while (a < a_end && b < b_end) {
            RunPair pair = compare_runs(bounds, a, b, (int)W);
            int high = max(root_a, root_b);
            parent[pair.touch ? min(root_a, root_b) : high] = high;
            root_a = pair.touch ? high : root_a;
            parent[a] = root_a;
            a += pair.a_done;
            b += pair.b_done;
            root_a = pair.a_done ? a : root_a;
            root_b = find_root_shallow(parent, min(b, b_end - 1));  /* unused once b reaches b_end */
        }
        for (; a < a_end; a++) {  /* past the lower row's last run: the rest are their own roots */
            parent[a] = root_a;
            root_a = a + 1;
        }
        lower_count = count;
    }
}

/* The last row of every strip but the last merges with the first row of the strip below. */
__kernel void label_merge_strips(__global const int *bounds, __global const int *counts,
                                 __global volatile int *parent, long W, long H, long rows, long slots)
{
    long y = (get_global_id(0) + 1) * rows - 1;
    if (y + 1 >= H) return;
    int a = (int)(y * slots), a_end = a + counts[y], b = a + (int)slots, b_end = b + counts[y + 1];
    while (a < a_end && b < b_end) {
        RunPair pair = compare_runs(bounds, a, b, (int)W);
        if (pair.touch) merge_shared(parent, a, b);
        a += pair.a_done;
        b += pair.b_done;
    }
}

/* Every pixel gets its component's label, the last address of its run's root. One work-item per row:
 * first every run finds its root (consecutive runs often share a parent, and then one find serves
 * them) and keeps the label in run_label; then the row's pixels are written without branches, each
 * taking the label of the run counted so far or -1. Other rows' work-items may re-point runs of this
 * row's trees meanwhile, but only ever at an ancestor, so plain (non-volatile) accesses stay correct. */
__kernel void label_flatten(__global const uchar *mask, __global const int *bounds,
                            __global const int *counts, __global int *parent, __global int *run_label,
                            __global int *label, long W, long H, long slots)
{
    long y = get_global_id(0);
    if (y >= H) return;
    int first = (int)(y * slots), count = counts[y];
    int previous = -1, root = -1, value = -1;
    for (int a = first; a < first + count; a++) {
        int up = parent[a];
        if (up != previous) {
            previous = up;
            root = find_root_alone(parent, up);
            value = bounds[2 * (long)root + 1] - 1;
            /* Point the whole path at the root, so later finds in this tree take one step. */
            for (int k = up; k != root;) {
                int next = parent[k];
                parent[k] = root;
                k = next;
            }
        }
        parent[a] = root;
        run_label[a] = value;
    }
    /* ended: runs of the row that end before pixel x, so a foreground pixel's run is first + ended (for
     * a background pixel that may be the slot after the row's runs, read but not used). */
    __global const uchar *row_mask = mask + y * W;
    __global const int *row_labels = run_label + first;
    __global int *row_out = label + y * W;
    int x = 0, ended = 0, previous_here = 0;
#ifdef __ENDIAN_LITTLE__
    /* Eight pixels at a time, pixel x + j as byte j of a ulong holding 1 where it is foreground: the
     * ends of runs are bytes that follow a foreground byte, and one multiplication by 0x0101...01 sums
     * them up to every byte. */
    const ulong ones = 0x0101010101010101UL, low7 = 0x7f7f7f7f7f7f7f7fUL;
    for (; x + 8 <= W; x += 8) {
        ulong bytes = as_ulong(vload8(0, row_mask + x));
        ulong here = ((((bytes & low7) + low7) | bytes) >> 7) & ones;  /* any non-zero byte is 1 */
        ulong ends = ((here << 8) | (ulong)previous_here) & ~here;
        ulong ended_by = ends * ones;
        int8 run = (int8)ended + convert_int8(as_uchar8(ended_by));
        int8 own = (int8)(row_labels[run.s0], row_labels[run.s1], row_labels[run.s2], row_labels[run.s3],
                          row_labels[run.s4], row_labels[run.s5], row_labels[run.s6], row_labels[run.s7]);
        vstore8(select((int8)(-1), own, convert_int8(as_uchar8(here)) != 0), 0, row_out + x);
        ended += (int)(ended_by >> 56);
        previous_here = (int)(here >> 56);
    }
#endif
    for (; x < W; x++) {
        int here = row_mask[x] != 0;
        ended += previous_here & !here;
        previous_here = here;
        int own = row_labels[ended];
        row_out[x] = here ? own : -1;
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
