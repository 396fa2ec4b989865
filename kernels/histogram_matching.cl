/* Histogram matching (vmcl/early/histogram_matching.py): a field's values moved so that their
 * distribution follows a reference field's, rank for rank. Both fields are binned over their joint span
 * [lo, hi], lo and hi the lesser minimum and the greater maximum of the two (device scalars, never
 * read back), so that one bin means the same values in both. */

inline float2 joint_span(__global const float *low_a, __global const float *low_b, __global const float *high_a,
                         __global const float *high_b)
{
    return (float2)(fmin(low_a[0], low_b[0]), fmax(high_a[0], high_b[0]));
}

/* Each value's place in the joint span, in [0, 1]; 0 everywhere when the span is a single value. NaN
 * stays NaN (the histogram does not count it). */
__kernel void unit_levels(__global const float *x, __global float *t, long n, __global const float *low_a,
                          __global const float *low_b, __global const float *high_a, __global const float *high_b)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float2 span = joint_span(low_a, low_b, high_a, high_b);
    float width = span.y - span.x;
    float v = x[i];
    t[i] = isnan(v) ? NAN : width > 0.0f ? clamp((v - span.x) / width, 0.0f, 1.0f) : 0.0f;
}

/* The share of a histogram's values below each bin's lower edge: cdf[0] = 0 ... cdf[bins] = 1 (all 0 for
 * an empty histogram). One work-item; the bins are few. */
__kernel void cumulate(__global const int *counts, __global float *cdf, int bins)
{
    if (get_global_id(0) != 0) return;
    long total = 0;
    for (int b = 0; b < bins; b++) total += counts[b];
    float scale = total > 0 ? 1.0f / (float)total : 0.0f;
    long running = 0;
    cdf[0] = 0.0f;
    for (int b = 0; b < bins; b++) {
        running += counts[b];
        cdf[b + 1] = (float)running * scale;
    }
}

/* Each value takes the reference's value of the same rank. Its rank is read off its own histogram's
 * cumulative share, linearly within its bin; the reference's value of that rank is read off the
 * reference's, again linearly within the bin. The value moves by the difference
 * of the two places, in bins, so a field matched to itself is returned exactly. */
__kernel void match_levels(__global const float *x, __global const float *t, __global const float *source_cdf,
                           __global const float *reference_cdf, __global float *out, long n, int bins,
                           __global const float *low_a, __global const float *low_b, __global const float *high_a,
                           __global const float *high_b)
{
    long i = get_global_id(0);
    if (i >= n) return;
    float u = t[i];
    if (isnan(u)) { out[i] = NAN; return; }
    float2 span = joint_span(low_a, low_b, high_a, high_b);
    float at = u * (float)bins;
    int b = min((int)at, bins - 1);
    float rank = mix(source_cdf[b], source_cdf[b + 1], clamp(at - (float)b, 0.0f, 1.0f));
    /* The first bin whose upper edge's share exceeds the rank holds values (its lower edge's share is
     * at most the rank); the highest rank lies at the top of the last bin that holds values. */
    float top = reference_cdf[bins], target = fmin(rank, top);
    int first = 0, last = bins - 1;
    while (first < last) {
        int middle = (first + last) / 2;
        float edge = reference_cdf[middle + 1];
        if (edge > target || edge >= top) last = middle; else first = middle + 1;
    }
    float below = reference_cdf[first], inside = reference_cdf[first + 1] - below;
    float place = (float)first + (inside > 0.0f ? clamp((target - below) / inside, 0.0f, 1.0f) : 0.5f);
    out[i] = x[i] + (place - at) * (span.y - span.x) / (float)bins;
}
