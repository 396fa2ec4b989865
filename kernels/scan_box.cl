/* scan_box.cl, driven by vmcl/cm/scan.py (box_sum).
 * The window sum of "Powerful primitive operations" (Scanning): for every pixel, the sum over the
 * (2r+1) x (2r+1) square around it, zero outside the field, in time independent of r.
 *
 * The paper's recipe: plus-scan the rows, and let each pixel take the scan values r in front of it and
 * r + 1 behind it; their difference P[x+r] - P[x-r-1] is the sum along the row. Then the same on the
 * columns. Each pass below keeps that difference as its scan advances (adding the element that enters
 * the window, subtracting the one that leaves), which fuses the scan and the two gets into one pass
 * over memory; for int32 the result is exact, for float32 it differs from the prefix form only by
 * rounding.
 *
 * Defines: T (float|int), VEC (1 or 16, box_cols only).
 */
#include "vmcl.h"

/* Output j's window is x[j - r .. j + r]: step j adds x[j + r], entering it, and subtracts x[j - r - 1],
 * leaving it, where those exist. Which of them exist changes only at j = n - r (enters_end: nothing
 * enters from there on) and j = r + 1 (leaves_start), so a pass walks the up to four stretches between
 * those points with a loop each, STEP(enter, leave) being one step at j with no bounds test. The only
 * cost that grows with r is then the r warm-up loads before step 0, which are cheaper than steps; a
 * single loop over n + r steps, each testing all three bounds, made a larger r cost r full steps. */
#define WINDOW_WALK(STEP, n)                                                               \
    {                                                                                      \
        long enters_end = max((n) - r, 0L), leaves_start = min(r + 1, (n));                \
        long j = 0;                                                                        \
        for (; j < min(enters_end, leaves_start); j++) { STEP(1, 0) }                      \
        for (; j < enters_end; j++) { STEP(1, 1) }                                         \
        for (; j < leaves_start; j++) { STEP(0, 0) }                                       \
        for (; j < (n); j++) { STEP(0, 1) }                                                \
    }

/* One step of row chain K, which slides over the row starting at bK. */
#define ROW_STEP(K, ENTER, LEAVE)                                                          \
    {                                                                                      \
        if (ENTER) w##K += x[b##K + j + r];                                                \
        if (LEAVE) w##K -= x[b##K + j - r - 1];                                            \
        out[b##K + j] = w##K;                                                              \
    }
#define ROWS_STEP(ENTER, LEAVE) \
    ROW_STEP(0, ENTER, LEAVE) ROW_STEP(1, ENTER, LEAVE) ROW_STEP(2, ENTER, LEAVE) ROW_STEP(3, ENTER, LEAVE)

/* Work-item g slides along rows 4g .. 4g+3 (interleaved: four independent chains hide the latency of
 * the dependent adds). Rows past the last are clamped to it and write the same values again. */
__kernel void box_rows(__global const T *x, __global T *out, long n, long lines, long r)
{
    long first = get_global_id(0) * 4;
    if (first >= lines) return;
    long b0 = first * n, b1 = min(first + 1, lines - 1) * n;
    long b2 = min(first + 2, lines - 1) * n, b3 = min(first + 3, lines - 1) * n;
    T w0 = 0, w1 = 0, w2 = 0, w3 = 0;
    for (long i = 0; i < min(r, n); i++) {  /* warm-up: x[0 .. r - 1], output 0's window before step 0 */
        w0 += x[b0 + i];
        w1 += x[b1 + i];
        w2 += x[b2 + i];
        w3 += x[b3 + i];
    }
    WINDOW_WALK(ROWS_STEP, n)
}

/* One step down the columns, VEC at a time; row i of the columns starts at base + i * W. */
#define COLS_STEP(ENTER, LEAVE)                                                            \
    {                                                                                      \
        if (ENTER) w += VLOAD(x + base + (size_t)(j + r) * W);                             \
        if (LEAVE) w -= VLOAD(x + base + (size_t)(j - r - 1) * W);                         \
        VSTORE(w, out + base + (size_t)j * W);                                             \
    }

/* Work-item (k, p) slides down columns [col0 + k*VEC, col0 + (k+1)*VEC) of plane p, VEC at a time so
 * every row step is one contiguous vector access. */
__kernel void box_cols(__global const T *x, __global T *out, long W, long H, long col0, long n_vec, long r)
{
    long k = get_global_id(0), p = get_global_id(1);
    if (k >= n_vec) return;
    size_t base = (size_t)p * H * W + col0 + k * VEC;
    VT w = (VT)0;
    for (long i = 0; i < min(r, H); i++) w += VLOAD(x + base + (size_t)i * W);  /* warm-up, as in box_rows */
    WINDOW_WALK(COLS_STEP, H)
}

/* The same sums for a GPU (vmcl/cm/scan.py takes these where the device is not a CPU): a walk per line
 * gives a 512 x 512 field 512 work-items, far too few for a GPU (box_rows was a quarter of an H200's
 * device time per frame, at 1% of its copy bandwidth). Here work-item (s, line) walks outputs
 * [s segment, (s + 1) segment) of its line, its first window summed whole; `segment` is at least the
 * window's width, so the warm-up at most doubles the loads. A walk this short rounds no worse than the
 * whole line's. */
__kernel void box_rows_segments(__global const T *x, __global T *out, long n, long lines, long r, long segment)
{
    long s = get_global_id(0), line = get_global_id(1), j0 = s * segment;
    if (j0 >= n || line >= lines) return;
    __global const T *row = x + line * n;
    __global T *dst = out + line * n;
    T w = 0;
    for (long t = max(j0 - r, 0L); t <= min(j0 + r, n - 1); t++) w += row[t];
    dst[j0] = w;
    for (long j = j0 + 1; j < min(j0 + segment, n); j++) {
        if (j + r < n) w += row[j + r];
        if (j - r - 1 >= 0) w -= row[j - r - 1];
        dst[j] = w;
    }
}

/* Work-item (column, s, plane) walks rows [s segment, (s + 1) segment) of its column: neighbouring
 * work-items read neighbouring columns, one contiguous access per step across them. */
__kernel void box_cols_segments(__global const T *x, __global T *out, long W, long H, long r, long segment)
{
    long column = get_global_id(0), s = get_global_id(1), p = get_global_id(2), j0 = s * segment;
    if (column >= W || j0 >= H) return;
    __global const T *col = x + (size_t)p * H * W + column;
    __global T *dst = out + (size_t)p * H * W + column;
    T w = 0;
    for (long t = max(j0 - r, 0L); t <= min(j0 + r, H - 1); t++) w += col[(size_t)t * W];
    dst[(size_t)j0 * W] = w;
    for (long j = j0 + 1; j < min(j0 + segment, H); j++) {
        if (j + r < H) w += col[(size_t)(j + r) * W];
        if (j - r - 1 >= 0) w -= col[(size_t)(j - r - 1) * W];
        dst[(size_t)j * W] = w;
    }
}
