"""NumPy oracles for the Connection Machine primitives, written for clarity, not speed."""

import itertools
import math

import numpy as np

UFUNCS = {"plus": np.add, "max": np.maximum, "min": np.minimum}
IDENTITIES = {
    "plus": lambda dtype: dtype.type(0),
    "max": lambda dtype: dtype.type(-np.inf) if dtype.kind == "f" else np.iinfo(dtype).min,
    "min": lambda dtype: dtype.type(np.inf) if dtype.kind == "f" else np.iinfo(dtype).max,
    "copy": lambda dtype: dtype.type(0),
}


def scan_line(line, op, exclusive, starts):
    """Segmented scan of one 1-D line; starts marks segment starts (the line start is one anyway)."""
    out = np.empty_like(line)
    bounds = list(np.flatnonzero(starts)) + [len(line)]
    if bounds[0] != 0:
        bounds.insert(0, 0)
    for a, b in itertools.pairwise(bounds):
        seg = line[a:b]
        inclusive = np.full_like(seg, seg[0]) if op == "copy" else UFUNCS[op].accumulate(seg)
        if exclusive:
            out[a] = IDENTITIES[op](line.dtype)
            out[a + 1:b] = inclusive[:-1]
        else:
            out[a:b] = inclusive
    return out


def scan(x, op="plus", axis=-1, exclusive=False, segments=None):
    moved = np.moveaxis(x, axis, -1)
    starts = np.zeros(moved.shape, bool) if segments is None else np.moveaxis(segments != 0, axis, -1)
    out = np.empty_like(moved)
    for index in np.ndindex(moved.shape[:-1]):
        out[index] = scan_line(moved[index], op, exclusive, starts[index])
    return np.moveaxis(out, -1, axis)


def box_sum(x, r, axes=(-2, -1)):
    """Window sums with zeros outside, from float64 (or int64) prefix sums."""
    acc = x.astype(np.float64 if x.dtype.kind == "f" else np.int64)
    for axis in axes:
        n = acc.shape[axis]
        prefix = np.cumsum(acc, axis=axis)
        prefix = np.concatenate([np.zeros_like(np.take(prefix, [0], axis=axis)), prefix], axis=axis)
        index = np.arange(n)
        acc = np.take(prefix, np.minimum(index + r + 1, n), axis=axis) - np.take(prefix, np.maximum(index - r, 0), axis=axis)
    return acc


def census_codes(image, size=(9, 7), margin=0.0):
    """Census codes as Python ints: bit set where a window pixel (border repeated) is below centre - margin."""
    height, width = image.shape
    rx, ry = size[0] // 2, size[1] // 2
    codes = np.zeros((height, width), dtype=object)
    for y in range(height):
        for x in range(width):
            code = 0
            for j in range(-ry, ry + 1):
                for i in range(-rx, rx + 1):
                    if i == 0 and j == 0:
                        continue
                    yy, xx = min(max(y + j, 0), height - 1), min(max(x + i, 0), width - 1)
                    code = (code << 1) | int(image[yy, xx] < image[y, x] - margin)
            codes[y, x] = code
    return codes


def semiglobal_sums(left, right, d_min, d_max, p1, p2, directions, outside, margin=0.0):
    """Semi-global matching on grey float images, edge gain 0: the (H, W, D) sums of the min-sum messages
    along ``directions`` of census Hamming costs (``outside`` where x - d leaves the image), and the costs."""
    height, width = left.shape
    depth = d_max - d_min + 1
    lc, rc = census_codes(left, margin=margin), census_codes(right, margin=margin)
    cost = np.full((height, width, depth), outside, np.int64)
    for y, x, k in itertools.product(range(height), range(width), range(depth)):
        xr = x - (d_min + k)
        if 0 <= xr < width:
            cost[y, x, k] = (lc[y, x] ^ rc[y, xr]).bit_count()
    total = np.zeros_like(cost)
    for dx, dy in directions:
        messages = np.zeros_like(cost)
        ys = range(height) if dy >= 0 else range(height - 1, -1, -1)
        xs = range(width) if dx >= 0 else range(width - 1, -1, -1)
        for y in ys:
            for x in xs:
                py, px = y - dy, x - dx
                if not (0 <= py < height and 0 <= px < width):
                    messages[y, x] = cost[y, x]
                    continue
                prev = messages[py, px]
                low = prev.min()
                shifted = np.full(depth + 2, np.iinfo(np.int64).max // 2)
                shifted[1:-1] = prev
                best = np.minimum.reduce([prev, shifted[:-2] + p1, shifted[2:] + p1, np.full(depth, low + int(max(p1, p2)))])
                messages[y, x] = cost[y, x] + best - low
        total += messages
    return total, cost


def semiglobal_winners(total, d_min, cost=None, poor=None):
    """Left winners (ties: smaller d) over the disparities whose right pixel is inside, and the right view's
    winners from the same sums; ``d_min - 1`` where none competes, for a left winner pressed against the
    image's edge (the last disparity inside where the range goes on), and for one at an end of the range
    (whose ``cost`` there exceeds ``poor``, when given), which the third output marks (out of range)."""
    height, width, depth = total.shape
    left = np.full((height, width), d_min - 1)
    right = np.full((height, width), d_min - 1)
    out_of_range = np.zeros((height, width), bool)
    for y, x in itertools.product(range(height), range(width)):
        ks = [k for k in range(depth) if 0 <= x - (d_min + k) < width]
        if ks:
            best = min(ks, key=lambda k: (total[y, x, k], k))
            pressed = (best == ks[-1] and ks[-1] < depth - 1) or (best == ks[0] and ks[0] > 0)
            at_end = depth > 1 and best in (0, depth - 1) and (cost is None or cost[y, x, best] > poor)
            out_of_range[y, x] = at_end and not pressed
            left[y, x] = d_min - 1 if pressed or at_end else d_min + best
        ks = [k for k in range(depth) if 0 <= x + d_min + k < width]
        if ks:
            right[y, x] = d_min + min(ks, key=lambda k: (total[y, x + d_min + k, k], k))
    return left, right, out_of_range


def _smoothed(plane, sigma):
    """The exact Gaussian of vmcl.early.filters.gaussian_taps with clamped borders, in float64."""
    from scipy import ndimage

    from vmcl.early.filters import gaussian_taps

    taps = gaussian_taps(sigma).astype(np.float64)
    return ndimage.correlate1d(ndimage.correlate1d(plane.astype(np.float64), taps, axis=1, mode="nearest"),
                               taps, axis=0, mode="nearest")


def _sampled(plane, sigma, step_y, step_x=None):
    """The exact Gaussian of ``plane`` at every ``step_y``-th row and ``step_x``-th column (default: step_y),
    from 0 to the first sample at or past the last pixel, the borders clamped."""
    step_x = step_y if step_x is None else step_x
    height, width = plane.shape
    padded = np.pad(plane, ((0, -(-(height - 1) // step_y) * step_y + 1 - height),
                            (0, -(-(width - 1) // step_x) * step_x + 1 - width)), mode="edge")
    return _smoothed(padded, sigma)[::step_y, ::step_x]


def _interpolated(coarse, shape, step_y, step_x=None):
    """A plane sampled at every step_y-th row and step_x-th column (default: step_y), bilinearly at every
    pixel of ``shape``."""
    from scipy import ndimage

    step_x = step_y if step_x is None else step_x
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64)
    return ndimage.map_coordinates(coarse, [ys / step_y, xs / step_x], order=1, mode="nearest")


def _five_point(plane):
    """The five-point stencil's derivatives (gx, gy) with clamped borders."""
    p = np.pad(plane, 2, mode="edge")
    return ((8 * (p[2:-2, 3:-1] - p[2:-2, 1:-3]) - p[2:-2, 4:] + p[2:-2, :-4]) / 12,
            (8 * (p[3:-1, 2:-2] - p[1:-3, 2:-2]) - p[4:, 2:-2] + p[:-4, 2:-2]) / 12)


def _centred(plane):
    """Centred differences (gx, gy) with clamped borders."""
    p = np.pad(plane, 1, mode="edge")
    return 0.5 * (p[1:-1, 2:] - p[1:-1, :-2]), 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1])


def texton_bank(lightness, sigmas=(1.0, 2.0)):
    """The texton filter bank of vmcl.early.boundary_probability, compressed, (H, W, 18)."""
    out = []
    for sigma in sigmas:
        s = _smoothed(lightness, sigma)
        p = np.pad(s, 1, mode="edge")
        gx, gy = _centred(s)
        gxx, gyy = p[1:-1, 2:] - 2 * s + p[1:-1, :-2], p[2:, 1:-1] - 2 * s + p[:-2, 1:-1]
        gxy = 0.25 * (p[2:, 2:] - p[2:, :-2] - p[:-2, 2:] + p[:-2, :-2])
        for k in range(4):
            c, si = np.cos(k * np.pi / 4), np.sin(k * np.pi / 4)
            out += [sigma * (gx * c + gy * si), sigma**2 * (gxx * c * c + 2 * gxy * c * si + gyy * si * si)]
        out.append(sigma**2 * (gxx + gyy))
    r = np.stack(out, axis=-1)
    n = np.linalg.norm(r, axis=-1, keepdims=True)
    return r * np.where(n > 0, np.log1p(n / 0.03) / np.where(n > 0, n, 1), 0)


def oriented_gradients(lab, labels, ntextons, scales, orientations=8, ratio=2.0, surround_sigma=10.0,
                       floor=0.02, sampled=True):
    """The boundary classifier's features (orientations, H, W, 12 len(scales)) from the (3, H, W) L*a*b*
    planes (each / 100) and the texton labels; the textons' histograms, their tensors and the surround sampled
    as the map samples them (vmcl.early.boundary_probability.sample_step; with ``sampled`` False, every
    smoothing exact at every pixel); the texture tensor integrated at the texture's scale; the
    surround is the Gaussian mean of each gradient's largest value over all orientations."""
    from vmcl.early.boundary_probability import sample_step

    plain, strongest = [], []
    for sigma in scales:
        grads = [_centred(_smoothed(p, sigma)) for p in lab]
        step = sample_step(ratio * sigma) if sampled else 1
        # The histograms, their tensor and its integration on the grid of every step-th pixel, interpolated.
        tex = [(_centred if step == 1 else _five_point)(_sampled((labels == k).astype(np.float64), ratio * sigma, step))
               for k in range(ntextons)]
        scale = ratio * sigma / step
        tx, txy, ty = (_interpolated(_smoothed(sum(scale**2 * a * b for a, b in pairs), scale), labels.shape, step)
                       for pairs in ([(gx, gx) for gx, _ in tex], [(gx, gy) for gx, gy in tex],
                                     [(gy, gy) for _, gy in tex]))
        per_orientation = []
        for o in range(orientations):
            c, s = np.cos(o * np.pi / orientations), np.sin(o * np.pi / orientations)
            f = [np.abs(sigma * (c * gx + s * gy)) for gx, gy in grads]
            f.append(np.sqrt(np.maximum(c * c * tx + 2 * c * s * txy + s * s * ty, 0)))
            per_orientation.append(np.stack(f, axis=-1))
        plain.append(np.stack(per_orientation))
        largest = 0.5 * (tx + ty) + np.sqrt(0.25 * (tx - ty) ** 2 + txy**2)
        strongest += [sigma * np.hypot(gx, gy) for gx, gy in grads] + [np.sqrt(np.maximum(largest, 0))]
    plain = np.concatenate(plain, axis=-1)
    strongest = np.stack(strongest, axis=-1)
    step = sample_step(surround_sigma) if sampled else 1
    surround = np.stack([_interpolated(_sampled(strongest[..., j], surround_sigma, step, 1), strongest.shape[:2],
                                       step, 1) for j in range(plain.shape[-1])], axis=-1)
    return np.concatenate([plain, np.sqrt(plain), np.sqrt(plain / (floor + surround))], axis=-1)


def pseudolikelihood(f, line_h, line_v, theta, *, data=None, confidence=None, edges=None, kind="smooth",
                     levels=None):
    """The negative log pseudolikelihood of (f, l) at natural parameters ``theta`` (vmcl.learn's order),
    from vmcl.mrf.energy alone: each conditional from the energy of the site's states (a pixel of the
    smooth kind: the quadratic through three values of its f; the constant kind: every level; a line
    site: on and off), scaled by 1 / T. Every site of the lattice is scored."""
    from vmcl import mrf

    f = np.asarray(f, np.float64)
    scale = theta["coupling"] if kind == "smooth" else 1.0
    beta = theta["line"] / scale if theta["line"] / scale > 0 else 1.0
    prior = mrf.LinePrior(**{k: theta[k] / scale / beta for k in ("line", "end", "continuation", "turn", "junction",
                                                                   "crossing", "parallel")})
    model = mrf.EnergyModel(alpha=theta["alpha"] / scale, beta=beta, prior=prior,
                            edge_gain=theta["edge_gain"] / scale / beta,
                            kappa=theta["coupling"] if kind == "constant" else 1.0)
    g = np.zeros_like(f) if data is None else np.asarray(data, np.float64)
    gamma = np.zeros(f.shape[:2]) if data is None else (np.ones(f.shape[:2]) if confidence is None else confidence)

    def u(field, lh, lv):
        return scale * mrf.energy(field, lh, lv, data=g, confidence=gamma, edges=edges, kind=kind, model=model)

    total = 0.0
    height, width = f.shape[:2]
    for y in range(height):
        for x in range(width):
            if kind == "smooth":
                ncomp = 1 if f.ndim == 2 else f.shape[2]
                for c in range(ncomp):
                    values = []
                    for v in (-1.0, 0.0, 1.0):
                        trial = f.copy()
                        if f.ndim == 2:
                            trial[y, x] = v
                        else:
                            trial[y, x, c] = v
                        values.append(u(trial, line_h, line_v))
                    a2 = (values[0] + values[2] - 2 * values[1]) / 2  # U = a2 v^2 + a1 v + a0
                    a1 = (values[2] - values[0]) / 2
                    if a2 <= 0:
                        continue  # no data and no bond: no conditional
                    mean = -a1 / (2 * a2)
                    value = f[y, x] if f.ndim == 2 else f[y, x, c]
                    total += a2 * (value - mean) ** 2 - 0.5 * np.log(a2 / np.pi)
            else:
                energies = []
                for level in levels:
                    trial = f.copy()
                    trial[y, x] = level
                    energies.append(u(trial, line_h, line_v))
                energies = np.array(energies)
                observed = u(f, line_h, line_v)
                total += observed - energies.min() + np.log(np.sum(np.exp(energies.min() - energies)))
    for lines, shape in ((line_h, (height, width - 1)), (line_v, (height - 1, width))):
        for y in range(shape[0]):
            for x in range(shape[1]):
                states = []
                for state in (False, True):
                    lh, lv = line_h.copy(), line_v.copy()
                    (lh if lines is line_h else lv)[y, x] = state
                    states.append(u(f, lh, lv))
                de = states[1] - states[0]
                on = bool(lines[y, x])
                total += np.logaddexp(0.0, de if on else -de)  # P(on) = 1 / (1 + e^dE)
    return total


# --- grouping (vmcl.group) --------------------------------------------------------------------------

STEPS = [(1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1)]  # E NE N NW W SW S SE


def edge_links(mask):
    """(H, W) uint8 link bits of an edge mask: 4-neighbours always, a diagonal one only where neither
    pixel sharing its corner is an edge (mixed adjacency)."""
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    padded = np.pad(mask, 1)

    def at(dx, dy):
        return padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]

    links = np.zeros((h, w), np.uint8)
    for k, (dx, dy) in enumerate(STEPS):
        linked = mask & at(dx, dy)
        if dx and dy:
            linked &= ~at(dx, 0) & ~at(0, dy)
        links |= (linked.astype(np.uint8) << k)
    return links


def trace_curves(mask):
    """A plain tracer: the edge pixels with at most two links, split at the others (branch pixels), as a
    set of frozensets of (x, y), plus the set of branch pixels. Components are found by walking the
    links between curve pixels."""
    links = edge_links(mask)
    degree = np.vectorize(lambda b: int(b).bit_count())(links) if links.size else links
    mask = np.asarray(mask, bool)
    curve = mask & (degree <= 2)
    seen = np.zeros(mask.shape, bool)
    curves = set()
    for y, x in zip(*np.nonzero(curve)):
        if seen[y, x]:
            continue
        stack, members = [(x, y)], []
        seen[y, x] = True
        while stack:
            cx, cy = stack.pop()
            members.append((int(cx), int(cy)))
            for k, (dx, dy) in enumerate(STEPS):
                nx, ny = cx + dx, cy + dy
                if links[cy, cx] >> k & 1 and curve[ny, nx] and not seen[ny, nx]:
                    seen[ny, nx] = True
                    stack.append((nx, ny))
        curves.add(frozenset(members))
    branches = {(int(x), int(y)) for y, x in zip(*np.nonzero(mask & (degree >= 3)))}
    return curves, branches


def structural_saliency(mask, tangent, strength, iterations, gap_attenuation, curvature_scale):
    """Sha'ashua and Ullman's network in NumPy (float64), element for element as
    kernels/structural_saliency.cl defines it; returns (pixel saliency (H, W), elements (8, H, W))."""
    mask = np.asarray(mask, bool)
    h, w = mask.shape
    links = edge_links(mask)
    step_angle = np.array([math.atan2(dy, dx) for dx, dy in STEPS])
    ys, xs = np.mgrid[0:h, 0:w]
    actual = np.stack([(links >> k) & 1 for k in range(8)]).astype(bool)

    def element_angle(k, y, x):
        t = tangent[y, x]
        own = actual[k, y, x] & np.isfinite(t)
        d = np.remainder(t - step_angle[k] + math.pi, 2 * math.pi) - math.pi
        oriented = np.where(np.abs(d) > math.pi / 2, t + math.pi, t)
        return np.where(own, oriented, step_angle[k])

    def turn(a, b):
        d = np.remainder(np.abs(a - b), 2 * math.pi)
        return np.where(d > math.pi, 2 * math.pi - d, d)

    sigma = np.zeros((8, h, w))
    rho = np.zeros((8, h, w))
    coupling = np.zeros((3, 8, h, w))
    qx, qy = np.zeros((8, h, w), int), np.zeros((8, h, w), int)
    for k, (dx, dy) in enumerate(STEPS):
        inside = (xs + dx >= 0) & (xs + dx < w) & (ys + dy >= 0) & (ys + dy < h)
        cx, cy = np.clip(xs + dx, 0, w - 1), np.clip(ys + dy, 0, h - 1)
        qx[k], qy[k] = cx, cy
        sigma[k] = np.where(actual[k], 0.5 * (strength + strength[cy, cx]), 0)
        rho[k] = np.where(actual[k], 1.0, gap_attenuation)
        own = element_angle(k, ys, xs)
        ds = math.sqrt(2) if k % 2 else 1.0
        for c in range(3):
            kk = (k + c + 7) % 8
            alpha = turn(own, element_angle(kk, cy, cx))
            crossing = actual[k] != actual[kk, cy, cx]
            alpha = np.where(crossing, np.maximum(0, alpha - math.pi / 8), alpha)
            with np.errstate(invalid="ignore"):
                f = np.where(alpha < math.pi / 2, np.exp(-curvature_scale * 2 * alpha * np.tan(alpha / 2) / ds), 0)
            coupling[c, k] = np.where(inside, f, 0)
    saliency = sigma.copy()
    for _ in range(iterations - 1):
        best = np.zeros((8, h, w))
        for k in range(8):
            for c in range(3):
                kk = (k + c + 7) % 8
                best[k] = np.maximum(best[k], coupling[c, k] * saliency[kk, qy[k], qx[k]])
        saliency = sigma + rho * best
    pixel = np.zeros((h, w))
    for k in range(8):
        back = np.max([saliency[(k + c) % 8] for c in (3, 4, 5)], axis=0)
        pixel = np.maximum(pixel, saliency[k] + back)
    return pixel, saliency
