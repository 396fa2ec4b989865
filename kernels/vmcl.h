/* vmcl.h: shared definitions for every kernel family.
 *
 * One work-item stands for one Connection Machine processor. Element types arrive as -D T=float|int
 * (plus VEC for vector widths) so each family is compiled once per type it is used with.
 *
 * File names: a family is named after the host module that drives it (scan.cl: vmcl/cm/scan.py),
 * prefixed with its package where two modules share a name (cm_filters.cl, early_filters.cl) or where
 * a package's modules share the family (mrf.cl: vmcl/mrf; mrf_data.cl: vmcl/mrf/data.py), and suffixed
 * where one module drives two families (scan_box.cl). A module may launch a family another module owns
 * (noise.py reads edges.cl's histogram; sign_correlation.py uses motion.cl's kernels).
 */
#ifndef VMCL_H
#define VMCL_H

#define OP_PLUS 0
#define OP_MAX 1
#define OP_MIN 2
#define OP_COPY 3
#define OP_AND 4
#define OP_OR 5

/* Vector type of width VEC (1 = the scalar itself) and its load/store, for kernels that let one
 * work-item stand for VEC adjacent processors so the CPU's SIMD lanes and a GPU's memory coalescing
 * both see contiguous accesses. */
#define VCAT_(a, b) a##b
#define VCAT(a, b) VCAT_(a, b)
#ifndef VEC
#define VEC 1
#endif
#if VEC == 1
#define VT T
#define VIT int
#define VLOAD(p) (*(p))
#define VSTORE(v, p) (*(p) = (v))
#define VFLAGS(p) ((int)(*(p)))
#else
#define VT VCAT(T, VEC)
#define VIT VCAT(int, VEC)
#define VLOAD(p) VCAT(vload, VEC)(0, (p))
#define VSTORE(v, p) VCAT(vstore, VEC)((v), 0, (p))
#define VFLAGS(p) VCAT(convert_int, VEC)(VCAT(vload, VEC)(0, (p)))
#endif

/* VEC floats of a row of W, row[a .. a + VEC), the row's end values repeated past its ends: one load
 * inside the row, one value broadcast wholly past an end, a gather only where the chunk straddles an end
 * (so kernels that take VEC pixels per work-item keep vector steps at a row's borders). */
#if VEC == 1
#define VFLOAT float
#else
#define VFLOAT VCAT(float, VEC)
#endif
inline VFLOAT clamped_chunk(__global const float *row, long a, long W)
{
#if VEC == 1
    return row[clamp(a, 0L, W - 1)];
#else
    if (a >= 0 && a + VEC <= W) return VCAT(vload, VEC)(0, row + a);
    if (a + VEC <= 0) return (VFLOAT)row[0];
    if (a >= W) return (VFLOAT)row[W - 1];
    float t[VEC];
    for (int i = 0; i < VEC; i++) t[i] = row[clamp(a + i, 0L, W - 1)];
    return VCAT(vload, VEC)(0, t);
#endif
}

/* Extremes of T, the identities of max and min. The host passes T_IS_FLOAT with T. */
#if T_IS_FLOAT
#define T_LOWEST (-INFINITY)
#define T_HIGHEST (INFINITY)
#else
#define T_LOWEST INT_MIN
#define T_HIGHEST INT_MAX
#endif

/* Flat index of (x, y) in plane p of a W x H stack. */
#define IDX3(x, y, p, W, H) (((size_t)(p) * (size_t)(H) + (size_t)(y)) * (size_t)(W) + (size_t)(x))

#endif
