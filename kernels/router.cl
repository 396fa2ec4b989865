/* router.cl: the Connection Machine's router, seed section "Powerful primitive operations" (Routing):
 * parallel reads (get) and writes (send) at arbitrary addresses, with messages to one destination
 * combined by an operator.
 *
 * send is deterministic for every operator and type, floats included, without float atomics: senders
 * are bucketed by destination (integer atomics count and place them), each bucket is sorted by sender
 * index, and each destination folds its messages in sender order, exactly as a sequential loop over the
 * senders would (so a float sum equals np.add.at's, bit for bit).
 *
 * Defines: T (uchar|int|float), COMBINE_OP (0 overwrite, OP_PLUS, OP_MAX, OP_MIN, OP_AND, OP_OR).
 */
#include "vmcl.h"

#define OP_OVERWRITE 100

#if COMBINE_OP == OP_OVERWRITE
#define FOLD(acc, v) (v)
#elif COMBINE_OP == OP_PLUS
#define FOLD(acc, v) ((acc) + (v))
/* Floats fold by fmax and fmin, which pass over NaN (as reduce.cl and scan.cl do): OpenCL's max and min
 * leave NaN undefined, and on PoCL a NaN reset the fold, so the answer hung on the senders' order. */
#elif COMBINE_OP == OP_MAX && T_IS_FLOAT
#define FOLD(acc, v) fmax((acc), (v))
#elif COMBINE_OP == OP_MIN && T_IS_FLOAT
#define FOLD(acc, v) fmin((acc), (v))
#elif COMBINE_OP == OP_MAX
#define FOLD(acc, v) max((acc), (v))
#elif COMBINE_OP == OP_MIN
#define FOLD(acc, v) min((acc), (v))
#elif COMBINE_OP == OP_AND
#define FOLD(acc, v) ((acc) & (v))
#elif COMBINE_OP == OP_OR
#define FOLD(acc, v) ((acc) | (v))
#endif

__kernel void gather(__global const T *field, __global const int *address, __global T *out, long n)
{
    long i = get_global_id(0);
    if (i < n) out[i] = field[address[i]];
}

__kernel void count_senders(__global const int *address, __global int *counts, long n)
{
    long i = get_global_id(0);
    if (i < n) atomic_inc(&counts[address[i]]);
}

/* cursor starts as each bucket's offset; the order within a bucket is fixed later by sort_buckets. */
__kernel void place_senders(__global const int *address, __global int *cursor, __global int *slots, long n)
{
    long i = get_global_id(0);
    if (i < n) slots[atomic_inc(&cursor[address[i]])] = (int)i;
}

/* Heapsort of bucket d's sender indices: O(k log k) even for a bucket holding every sender. */
inline void sift_down(__global int *a, int root, int end)
{
    for (;;) {
        int child = 2 * root + 1;
        if (child >= end) return;
        if (child + 1 < end && a[child + 1] > a[child]) child++;
        if (a[root] >= a[child]) return;
        int t = a[root]; a[root] = a[child]; a[child] = t;
        root = child;
    }
}

__kernel void sort_buckets(__global const int *offsets, __global const int *counts, __global int *slots, long size)
{
    long d = get_global_id(0);
    if (d >= size) return;
    int k = counts[d];
    if (k < 2) return;
    __global int *a = slots + offsets[d];
    for (int root = k / 2 - 1; root >= 0; root--) sift_down(a, root, k);
    for (int end = k - 1; end > 0; end--) {
        int t = a[0]; a[0] = a[end]; a[end] = t;
        sift_down(a, 0, end);
    }
}

/* Destination d folds its messages in sender order; with none it keeps `fill`. */
__kernel void combine_buckets(__global const T *values, __global const int *offsets, __global const int *counts,
                              __global const int *slots, __global T *out, T fill, long size)
{
    long d = get_global_id(0);
    if (d >= size) return;
    int k = counts[d];
    if (k == 0) {
        out[d] = fill;
        return;
    }
    __global const int *s = slots + offsets[d];
    T acc = values[s[0]];
    for (int j = 1; j < k; j++) acc = FOLD(acc, values[s[j]]);
    out[d] = acc;
}
