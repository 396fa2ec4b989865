/* integrate.cl: the integration stage's output, seed sections "The Vision Machine System" and
 * "Organization of integration". Each cue (stereo, motion, colour, texture ...) has been restored by its own
 * line-process MRF coupled to the brightness edges; here their line processes meet on the pixel grid.
 * One work-item per pixel (per CM processor), over a (W, H) grid; ids past the field idle.
 *
 *   boundary    a line process as a 0/1 pixel map: (x, y) is on when the site to its right (line_h) or
 *               below it (line_v) is on (the convention of vmcl.scenes' non-depth labels); the stereo
 *               matcher takes it as the barriers of its second pass
 *   start_support, mark_cue, mark_cue_owned
 *               the cue-support bitmask of every pixel: whether a brightness edge lies on it, and which
 *               cues put a line next to it (one launch per cue; owned: on the side an owner field picks)
 *   rule_labels each supported pixel's label by the cues' rules: the "cartoon"
 *
 * Line fields: line_h is (H, W - 1), line_v is (H - 1, W), uint8 0/1, as vmcl.mrf.restore returns them.
 * Defines (from vmcl.integrate, the one place that names them): BIT_BRIGHTNESS; NRULES, RULE_MASKS and
 * RULE_CODES, the rule labelling of every registered cue (vmcl.labels.rule_label).
 */

inline int on_boundary(__global const uchar *line_h, __global const uchar *line_v, long x, long y, long W, long H)
{
    return (x < W - 1 && line_h[y * (W - 1) + x]) || (y < H - 1 && line_v[y * W + x]);
}

__kernel void boundary(__global const uchar *line_h, __global const uchar *line_v, __global uchar *out,
                       long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    out[y * W + x] = (uchar)on_boundary(line_h, line_v, x, y, W, H);
}

/* The support map starts as the brightness edges' bit (or nothing without edges); each cue's line
 * process then adds its bit. */
__kernel void start_support(__global const uchar *edges, int with_edges, __global uchar *support, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    support[i] = (uchar)((with_edges && edges[i]) ? BIT_BRIGHTNESS : 0);
}

__kernel void mark_cue(__global const uchar *line_h, __global const uchar *line_v, int bit,
                       __global uchar *support, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    if (on_boundary(line_h, line_v, x, y, W, H)) support[(size_t)y * W + x] |= (uchar)bit;
}

/* The same, with each line site's mark on its owner's side: the pixel of the two whose owner field is
 * larger (the nearer surface's, for a disparity: an occluding contour belongs to the occluder). Equal or
 * NaN owners keep the left or upper pixel, as mark_cue does. */
__kernel void mark_cue_owned(__global const uchar *line_h, __global const uchar *line_v, int bit,
                             __global const float *owner, __global uchar *support, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    float o = owner[i];
    int marked = (x < W - 1 && line_h[y * (W - 1) + x] && !(owner[i + 1] > o))
              || (x > 0 && line_h[y * (W - 1) + x - 1] && o > owner[i - 1])
              || (y < H - 1 && line_v[y * W + x] && !(owner[i + W] > o))
              || (y > 0 && line_v[(y - 1) * W + x] && o > owner[i - W]);
    if (marked) support[i] |= (uchar)bit;
}

/* The rule labels: the physical reading of the support, most specific first (vmcl.labels.RULE_PRECEDENCE):
 * rule k gives label rule_codes[k] to a pixel with a bit of rule_masks[k] (the bits of the cues whose
 * lines stand for that label: stereo and motion for an occluding contour, colour for albedo, texture for
 * a texture boundary). A brightness edge no cue supports stays unlabelled (shadow, shading, fold or
 * texture element). */
__constant int rule_masks[NRULES] = {RULE_MASKS};
__constant uchar rule_codes[NRULES] = {RULE_CODES};

__kernel void rule_labels(__global const uchar *support, __global uchar *labels, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    uchar label = 0;
    for (int k = 0; k < NRULES; k++) {
        if (support[i] & rule_masks[k]) {
            label = rule_codes[k];
            break;
        }
    }
    labels[i] = label;
}
