/* mrf_data.cl: the MRF stage's data and its confidence gamma_i, from the early modules' measurements
 * (seed section "Organization of integration": stereo and motion are "noisy and sparse"). One work-item
 * per pixel over a flat range; ids past the field idle.
 *
 *   score_confidence  gamma = weight * clamp((score - floor) / (1 - floor), 0, 1), 0 where no score:
 *                     a measurement whose matching score barely clears chance pulls nothing
 *   backfill          the primary measurement where it has one (gamma 1), else the secondary with
 *                     its own gamma (0 where it has none either): sparse precise matches kept, the
 *                     gaps filled by dense ones
 *   mask_confidence   gamma = weight where the measurement exists, masked_weight where it exists and the
 *                     mask is set (a value filled in rather than measured), 0 where it does not exist
 *
 * Fields hold NCOMP floats per pixel (1: disparity, 2: flow); a pixel has a measurement when every
 * component is finite.
 */

#ifndef NCOMP
#define NCOMP 1
#endif

__kernel void score_confidence(__global const float *score, __global float *gamma, float floor, float weight,
                               long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    float s = score[i];
    gamma[i] = isfinite(s) ? weight * clamp((s - floor) / (1.0f - floor), 0.0f, 1.0f) : 0.0f;
}

__kernel void backfill(__global const float *primary, __global const float *secondary,
                       __global const float *secondary_gamma, __global float *data, __global float *gamma,
                       long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    int has = 1;
    for (int c = 0; c < NCOMP; ++c)
        has &= isfinite(primary[i * NCOMP + c]);
    for (int c = 0; c < NCOMP; ++c)
        data[i * NCOMP + c] = has ? primary[i * NCOMP + c] : secondary[i * NCOMP + c];
    int secondary_has = 1;
    for (int c = 0; c < NCOMP; ++c)
        secondary_has &= isfinite(secondary[i * NCOMP + c]);
    float g2 = secondary_gamma[i];
    gamma[i] = has ? 1.0f : (secondary_has && isfinite(g2) ? g2 : 0.0f);
}

__kernel void mask_confidence(__global const float *data, __global const uchar *mask, __global float *gamma,
                              float weight, float masked_weight, long size)
{
    long i = get_global_id(0);
    if (i >= size) return;
    int has = 1;
    for (int c = 0; c < NCOMP; ++c)
        has &= isfinite(data[i * NCOMP + c]);
    gamma[i] = has ? (mask[i] ? masked_weight : weight) : 0.0f;
}
