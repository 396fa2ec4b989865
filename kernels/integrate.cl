/* integrate.cl: the integration stage's output, seed sections "The Vision Machine System" and
 * "Organization of integration". Each cue (depth, motion, colour, texture) has been restored by its own
 * line-process MRF coupled to the brightness edges; here their line processes meet on the pixel grid.
 * One work-item per pixel (per CM processor), over a (W, H) grid; ids past the field idle.
 *
 *   boundary    a line process as a 0/1 pixel map: (x, y) is on when the site to its right (line_h) or
 *               below it (line_v) is on (the convention of vmcl.scenes' non-depth labels); the stereo
 *               matcher takes it as the barriers of its second pass
 *   integrate   the cue-support bitmask of every pixel (which cues put a line next to it, and whether a
 *               brightness edge lies on it) and its label: the "cartoon"
 *
 * Line fields: line_h is (H, W - 1), line_v is (H - 1, W), uint8 0/1, as vmcl.mrf.restore returns them.
 * Defines (from vmcl.integrate, the one place that names them): the cue bits BIT_STEREO, BIT_MOTION,
 * BIT_COLOUR, BIT_TEXTURE, BIT_BRIGHTNESS and the vmcl.scenes.Label codes LABEL_DEPTH, LABEL_ALBEDO,
 * LABEL_TEXTURE.
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

/* A cue whose bit is not in `present` has no line process; its buffers are placeholders never read. */
__kernel void integrate(__global const uchar *stereo_h, __global const uchar *stereo_v,
                        __global const uchar *motion_h, __global const uchar *motion_v,
                        __global const uchar *colour_h, __global const uchar *colour_v,
                        __global const uchar *texture_h, __global const uchar *texture_v,
                        __global const uchar *edges, int present,
                        __global uchar *support, __global uchar *labels, long W, long H)
{
    long x = get_global_id(0), y = get_global_id(1);
    if (x >= W || y >= H) return;
    size_t i = (size_t)y * W + x;
    int bits = 0;
    if ((present & BIT_STEREO) && on_boundary(stereo_h, stereo_v, x, y, W, H)) bits |= BIT_STEREO;
    if ((present & BIT_MOTION) && on_boundary(motion_h, motion_v, x, y, W, H)) bits |= BIT_MOTION;
    if ((present & BIT_COLOUR) && on_boundary(colour_h, colour_v, x, y, W, H)) bits |= BIT_COLOUR;
    if ((present & BIT_TEXTURE) && on_boundary(texture_h, texture_v, x, y, W, H)) bits |= BIT_TEXTURE;
    if ((present & BIT_BRIGHTNESS) && edges[i]) bits |= BIT_BRIGHTNESS;
    /* The physical reading of the support, most specific first: a jump of depth or of motion is an
     * occluding contour whatever else changes there; a change of hue is a change of albedo (shadows and
     * shading leave H = R / (R + G) unchanged); a change of texture alone is a texture boundary. A
     * brightness edge no cue supports stays unlabelled (shadow, shading, fold or texture element). */
    uchar label = 0;
    if (bits & (BIT_STEREO | BIT_MOTION)) label = LABEL_DEPTH;
    else if (bits & BIT_COLOUR) label = LABEL_ALBEDO;
    else if (bits & BIT_TEXTURE) label = LABEL_TEXTURE;
    support[i] = (uchar)bits;
    labels[i] = label;
}
