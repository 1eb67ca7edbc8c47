"""The per-pixel ray kernel: nearest surface, textured, lit (numba, compiled once to disk).

Two steps per frame, the second spread over the CPUs (numba's threads, the batches
of rays split between them: :func:`sim.renderer.set_render_threads`):

1. :func:`bin_primitives`: the azimuths around the robot are cut into ``W`` wedges
   (fixed to the robot's heading). Each primitive facing the camera is listed in
   the wedges its floor-plan outline spans, with its least distance from the
   camera; a wall face that spans a whole wedge from the floor to above every
   other surface hides what lies beyond its far end in that wedge, so farther
   primitives are left out. A few candidates per wedge remain.
2. :func:`trace`: each pixel's ray (the camera model's bearing, precomputed once per
   camera with the pixel's neighbours and anti-aliasing rays, turned by the camera's
   rotation as it is traced) is tested against its wedge's candidates, the floor,
   the ceilings and the sky; the nearest hit is textured (bilinear in the two mip
   levels around the pixel's footprint, blended: trilinear filtering) and lit.
   The rays go in batches of :data:`_BATCH`: first the surface each ray of the batch
   meets and where (texture, coordinates, footprint, light), then the texture samples
   of the whole batch in a short loop of its own. Texturing is a long chain of
   dependent steps (mip level, texel address, texel reads, blends); in the short loop
   the processor works on several rays' chains at once, where one long loop body per
   ray left it waiting on each (the batches took a frame's main pass from 14.9 to
   13.6 ms, the same image). Each batch writes only its own rays' outputs, so the
   image does not depend on how the batches are shared between threads.

Primitive ids: vertical quads ``[0, Q)``, horizontal quads ``[Q, Q+F)``, cylinders,
then spheres (see :mod:`sim.surfaces` for what they are).
"""

from __future__ import annotations

import math

import numba
import numpy as np

_EPS = 1e-9
_MIN_T = 1e-4
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}
"""Fast-math flags without "no infinities, no NaN" (the kernel compares with inf)."""
_SKY = -1_000_000
_LAMP = -2_000_000
_OUTSIDE = -3_000_000
_AA = 2
"""Edge pixels are the mean of _AA x _AA rays on a regular grid inside the pixel."""
_BLEND_BAND = 0.3
"""Width of the band of mip levels (in levels) over which two levels are blended."""
_BATCH = 256
"""Rays per batch: the surfaces a batch of rays meets are all found, then all textured."""


@numba.njit(cache=True, error_model="numpy")
def _wedges_of(a0: float, a1: float, wedges: int) -> tuple[int, int]:
    """First wedge and count of wedges the angular interval [a0, a0 + (a1 - a0) mod ...] spans.

    ``a0``, ``a1``: azimuths relative to the robot heading, rad; the interval is the
    shorter way from ``a0`` to ``a1``.
    """
    turn = (a1 - a0 + math.pi) % (2.0 * math.pi) - math.pi
    lo = a0 if turn > 0 else a0 + turn
    width = 2.0 * math.pi / wedges
    k0 = math.floor((lo + math.pi) / width)
    k1 = math.floor((lo + abs(turn) + math.pi) / width)
    return k0, k1 - k0 + 1


@numba.njit(cache=True, error_model="numpy")
def _seg_dist(px: float, py: float, ax: float, ay: float, dx: float, dy: float,
              length: float) -> float:
    s = min(max((px - ax) * dx + (py - ay) * dy, 0.0), length)
    return math.hypot(px - ax - s * dx, py - ay - s * dy)


@numba.njit(cache=True, error_model="numpy")
def bin_primitives(ox, oy, yaw, wedges, max_height, quad_a, quad_d, quad_len, quad_n, quad_z,
                   flat_c, flat_ax, flat_half, cyl_c, cyl_r, sph_c, sph_r):
    """Candidates per wedge (step 1 of the module docstring).

    Returns:
        start: (W + 1,) int64, wedge k's candidates are ``ids[start[k]:start[k+1]]``.
        ids: (E,) int64 primitive ids.
    """
    nq, nf, nc, ns = quad_a.shape[0], flat_c.shape[0], cyl_c.shape[0], sph_c.shape[0]
    n = nq + nf + nc + ns
    first = np.zeros(n, np.int64)
    count = np.zeros(n, np.int64)
    dmin = np.zeros(n)
    width = 2.0 * math.pi / wedges
    occ = np.full(wedges, np.inf)
    for q in range(nq):
        ax, ay = quad_a[q, 0], quad_a[q, 1]
        if (ox - ax) * quad_n[q, 0] + (oy - ay) * quad_n[q, 1] <= 0.0:
            continue
        dx, dy, length = quad_d[q, 0], quad_d[q, 1], quad_len[q]
        bx, by = ax + length * dx, ay + length * dy
        d = _seg_dist(ox, oy, ax, ay, dx, dy, length)
        dmin[q] = d
        if d < 1e-6:
            first[q], count[q] = 0, wedges
            continue
        k0, c = _wedges_of(math.atan2(ay - oy, ax - ox) - yaw,
                           math.atan2(by - oy, bx - ox) - yaw, wedges)
        first[q], count[q] = k0, c
        if quad_z[q, 0] > 0.0 or quad_z[q, 1] < max_height or c < 3:
            continue
        # A full-height face hides what lies beyond it in the wedges it spans wholly.
        qx, qy = ax - ox, ay - oy
        cross_qd = qx * dy - qy * dx
        for j in range(1, c - 1):
            k = k0 + j
            far = 0.0
            for edge in range(2):
                ang = -math.pi + (k + edge) * width + yaw
                rx, ry = math.cos(ang), math.sin(ang)
                den = rx * dy - ry * dx
                far = max(far, cross_qd / den if abs(den) > _EPS else np.inf)
            kk = k % wedges
            if far < occ[kk]:
                occ[kk] = far
    for f in range(nf):
        cx, cy = flat_c[f, 0], flat_c[f, 1]
        reach = math.hypot(flat_half[f, 0], flat_half[f, 1])
        d = math.hypot(cx - ox, cy - oy)
        i = nq + f
        dmin[i] = max(d - reach, 0.0)
        if d <= reach:
            first[i], count[i] = 0, wedges
            continue
        half = math.asin(min(reach / d, 1.0))
        centre = math.atan2(cy - oy, cx - ox) - yaw
        first[i], count[i] = _wedges_of(centre - half, centre + half, wedges)
    for t in range(nc + ns):
        if t < nc:
            cx, cy, r = cyl_c[t, 0], cyl_c[t, 1], cyl_r[t]
        else:
            cx, cy, r = sph_c[t - nc, 0], sph_c[t - nc, 1], sph_r[t - nc]
        i = nq + nf + t
        d = math.hypot(cx - ox, cy - oy)
        dmin[i] = max(d - r, 0.0)
        if d <= r * 1.001:
            first[i], count[i] = 0, wedges
            continue
        half = math.asin(r / d)
        centre = math.atan2(cy - oy, cx - ox) - yaw
        first[i], count[i] = _wedges_of(centre - half, centre + half, wedges)
    sizes = np.zeros(wedges, np.int64)
    for i in range(n):
        for j in range(count[i]):
            k = (first[i] + j) % wedges
            if dmin[i] <= occ[k]:
                sizes[k] += 1
    start = np.zeros(wedges + 1, np.int64)
    for k in range(wedges):
        start[k + 1] = start[k] + sizes[k]
    ids = np.empty(start[wedges], np.int64)
    fill = start[:-1].copy()
    for i in range(n):
        for j in range(count[i]):
            k = (first[i] + j) % wedges
            if dmin[i] <= occ[k]:
                ids[fill[k]] = i
                fill[k] += 1
    return start, ids


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST, inline="always")
def _bilinear(texels, off, w, h, u, v):
    """Bilinear sample at texture coordinates (u, v) in [0, 1] of a ``w`` x ``h`` level.

    ``off`` is the level's texel (0, 0) in ``texels``; its rows are ``w + 2`` apart and
    it has a one-texel border (:mod:`sim._atlas`: wrap-around for a tiling texture,
    clamped otherwise), so the four texels are read without wrapping their indices.
    """
    # x = u * w - 0.5 is in [-0.5, w - 0.5]: x + 1 > 0, so int() is floor() + 1.
    x = u * w + 0.5
    y = v * h + 0.5
    xi = int(x)
    yi = int(y)
    fx, fy = x - xi, y - yi
    stride = w + 2
    i = off + (yi - 1) * stride + (xi - 1)
    a, b = texels[i], texels[i + 1]
    c, d = texels[i + stride], texels[i + stride + 1]
    top = a + (b - a) * fx
    bottom = c + (d - c) * fx
    return top + (bottom - top) * fy


@numba.njit(cache=True, error_model="numpy", inline="always")
def _repeat_flips(iu, iv, surface):
    """Two pseudo-random bits for the repeat (iu, iv) of a tiling texture on ``surface``:
    bit 0 mirrors the repeat in u, bit 1 in v (a hash of the three integers)."""
    h = (iu * 73856093) ^ (iv * 19349663) ^ (surface * 83492791)
    h ^= h >> 13
    h *= 1274126177
    return (h >> 17) & 3


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST, inline="always")
def _sample(texels, levels, level_count, wraps, tex, u, v, footprint_uv, surface):
    """Sample of texture ``tex`` at (u, v) for a footprint of ``footprint_uv`` (u units).

    "Brilinear" filtering: the mip level is ``log2(footprint in texels)`` (approximated);
    within :data:`_BLEND_BAND` of the middle between two levels both are sampled and
    blended (no visible seam where the level changes), elsewhere the nearer one alone
    (half the cost of trilinear filtering, as GPUs do).

    A tiling texture is mirrored in u and/or v per repeat, at random but the same for
    every frame (:func:`_repeat_flips` of the repeat's index and ``surface``, an integer
    naming the surface). A tiling texture wraps seamlessly, so its mirror image does
    too; the floor, ceiling and walls then do not repeat exactly every period. They
    would otherwise: a 1.2 m ceiling tile and a 0.8 m floor tile make two places 4.8 m
    apart in a corridor the same picture, which no real building is (stains, wear,
    vents), and the front end rightly matches them. Another texture is clamped at its
    border.
    """
    # log2 of the footprint in texels, to within 0.09: the float's exponent plus its
    # mantissa's fraction (linear in the mantissa, as GPUs approximate it), read from
    # its bits (math.frexp is a library call: 1.4 ms per 800 x 600 frame).
    b = np.float64(max(footprint_uv * levels[tex, 0, 1], 1e-6)).view(np.int64)
    lod = float((b >> 52) - 1023) + float(b & 0xFFFFFFFFFFFFF) * (1.0 / 4503599627370496.0)
    last = level_count[tex] - 1
    # The nearest level, and within half the band of the middle between two levels,
    # the other one's weight (0.5 at the middle).
    l0 = int(min(max(lod + 0.5, 0.0), float(last)))
    e = lod - l0
    f = (abs(e) - 0.5 * (1.0 - _BLEND_BAND)) / _BLEND_BAND
    l1 = l0 + 1 if e > 0.0 else l0 - 1
    if l1 < 0 or l1 > last:
        f = 0.0
    if wraps[tex]:
        iu = math.floor(u)
        iv = math.floor(v)
        flips = _repeat_flips(iu, iv, surface)
        u -= iu
        v -= iv
        if flips & 1:
            u = 1.0 - u
        if flips & 2:
            v = 1.0 - v
    else:
        u = min(max(u, 0.0), 1.0)
        v = min(max(v, 0.0), 1.0)
    a = _bilinear(texels, levels[tex, l0, 0], levels[tex, l0, 1], levels[tex, l0, 2], u, v)
    if f <= 0.0:
        return a
    b = _bilinear(texels, levels[tex, l1, 0], levels[tex, l1, 1], levels[tex, l1, 2], u, v)
    return a + (b - a) * f


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST, inline="always")
def _light(values, origin, inv_res, x, y):
    """Bilinear light at floor-plan point (x, y); ``inv_res``: 1 / the cell side, 1/m."""
    h, w = values.shape
    fx = (x - origin[0]) * inv_res - 0.5
    fy = (y - origin[1]) * inv_res - 0.5
    c0 = min(max(math.floor(fx), 0), w - 2)
    r0 = min(max(math.floor(fy), 0), h - 2)
    ax = min(max(fx - c0, 0.0), 1.0)
    ay = min(max(fy - r0, 0.0), 1.0)
    top = values[r0, c0] * (1 - ax) + values[r0, c0 + 1] * ax
    bottom = values[r0 + 1, c0] * (1 - ax) + values[r0 + 1, c0 + 1] * ax
    return top * (1 - ay) + bottom * ay


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST, parallel=True)
def shade_rays(rays_c, R, wedge, angles, o, start, ids, quads, flats, cyls, sphs, planes, lamps,
               textures, light, sky, sun_w, grey_scale, dest, out_grey, out_depth, out_label):
    """Grey, distance and label of the surface each world ray meets first (in batches:
    module docstring).

    Args:
        rays_c: (M, 3) unit rays, camera frame; R: (3, 3) camera-to-world rotation (each
            ray is turned into the world frame as it is traced); wedge: (M,) their
            wedges; angles: (M,) the angular size of the area each one stands for, rad.
        o, start, ids, quads ... grey_scale: as :func:`trace` takes them.
        dest: (M,) where in ``out_grey`` and ``out_depth`` ray p's results go.
        out_grey, out_depth: outputs, written at ``dest``; out_label: (M,) int32 output.
            Labels: a primitive's id, -1 the floor, -2 - j ceiling j, :data:`_LAMP` - i
            lamp i, :data:`_SKY` the sky.
    """
    qa, qd, qlen, qn, qz, qtex, quv, qshade, qemit = quads
    fc, fax, fhalf, fz, fup, ftex, fuv = flats
    cc, cr, cz, ctex, cuv = cyls
    sc, sr, stex, suv = sphs
    origin, floor_map, floor_tex, floor_uv, ceil_lo, ceil_hi, ceil_z, ceil_tex, ceil_uv = planes
    lamp_map, lamp_c, lamp_ax, lamp_half, lamp_tex, lamp_emit = lamps
    texels, levels, level_count, wraps = textures
    lvalues, lorigin, lres = light
    nq, nf, nc = qa.shape[0], fc.shape[0], cc.shape[0]
    ox, oy, oz = o[0], o[1], o[2]
    fres = 0.01
    lamp_res = 0.1
    # Texture scales as reciprocals (u, v per metre): a multiplication per pixel, not a
    # division.
    floor_inv = 1.0 / floor_uv[:, :2]
    ceil_inv = 1.0 / ceil_uv[:, :2]
    quad_inv = 1.0 / quv[:, :2]
    flat_inv = 1.0 / fuv[:, :2]
    inv_lres = 1.0 / lres
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    rays = rays_c.shape[0]
    for batch in numba.prange((rays + _BATCH - 1) // _BATCH):
        first = batch * _BATCH
        count = min(_BATCH, rays - first)
        hit_tex = np.empty(_BATCH, np.int64)
        hit_surface = np.empty(_BATCH, np.int64)
        hit_uv = np.empty((_BATCH, 2))
        hit_foot = np.empty(_BATCH)
        hit_scale = np.empty(_BATCH)
        for b in range(count):
            p = first + b
            ray_x, ray_y, ray_z = rays_c[p, 0], rays_c[p, 1], rays_c[p, 2]
            rx = r00 * ray_x + r01 * ray_y + r02 * ray_z
            ry = r10 * ray_x + r11 * ray_y + r12 * ray_z
            rz = r20 * ray_x + r21 * ray_y + r22 * ray_z
            k = wedge[p]
            best = np.inf
            hit = -1
            hs = 0.0
            for e in range(start[k], start[k + 1]):
                i = ids[e]
                if i < nq:
                    dx, dy = qd[i, 0], qd[i, 1]
                    den = rx * dy - ry * dx
                    if abs(den) < _EPS:
                        continue
                    px, py = qa[i, 0] - ox, qa[i, 1] - oy
                    t = (px * dy - py * dx) / den
                    if t <= _MIN_T or t >= best:
                        continue
                    s = (px * ry - py * rx) / den
                    if s < 0.0 or s > qlen[i]:
                        continue
                    z = oz + t * rz
                    if z < qz[i, 0] or z > qz[i, 1]:
                        continue
                    best, hit, hs = t, i, s
                elif i < nq + nf:
                    f = i - nq
                    if rz * fup[f] >= 0.0 or (oz - fz[f]) * fup[f] <= 0.0:
                        continue
                    t = (fz[f] - oz) / rz
                    if t <= _MIN_T or t >= best:
                        continue
                    lx, ly = ox + t * rx - fc[f, 0], oy + t * ry - fc[f, 1]
                    if (abs(lx * fax[f, 0] + ly * fax[f, 1]) > fhalf[f, 0]
                            or abs(-lx * fax[f, 1] + ly * fax[f, 0]) > fhalf[f, 1]):
                        continue
                    best, hit = t, i
                elif i < nq + nf + nc:
                    c = i - nq - nf
                    qx, qy = ox - cc[c, 0], oy - cc[c, 1]
                    a2 = rx * rx + ry * ry
                    if a2 < _EPS:
                        continue
                    b2 = qx * rx + qy * ry
                    disc = b2 * b2 - a2 * (qx * qx + qy * qy - cr[c] * cr[c])
                    if disc < 0.0:
                        continue
                    t = (-b2 - math.sqrt(disc)) / a2
                    if t <= _MIN_T or t >= best:
                        continue
                    z = oz + t * rz
                    if z < cz[c, 0] or z > cz[c, 1]:
                        continue
                    best, hit = t, i
                else:
                    s_ = i - nq - nf - nc
                    qx, qy, qz_ = ox - sc[s_, 0], oy - sc[s_, 1], oz - sc[s_, 2]
                    b2 = qx * rx + qy * ry + qz_ * rz
                    disc = b2 * b2 - (qx * qx + qy * qy + qz_ * qz_ - sr[s_] * sr[s_])
                    if disc < 0.0:
                        continue
                    t = -b2 - math.sqrt(disc)
                    if t <= _MIN_T or t >= best:
                        continue
                    best, hit = t, i
            plane = -1
            if rz < 0.0:
                t = -oz / rz
                if t < best:
                    best, hit, plane = t, -1, 0
            elif rz > 0.0:
                for j in range(ceil_z.shape[0]):
                    t = (ceil_z[j] - oz) / rz
                    if t <= _MIN_T or t >= best:
                        continue
                    x, y = ox + t * rx, oy + t * ry
                    if ceil_lo[j, 0] <= x <= ceil_hi[j, 0] and ceil_lo[j, 1] <= y <= ceil_hi[j, 1]:
                        best, hit, plane = t, -1, 1 + j
            if hit < 0 and plane < 0:
                elevation = max(rz, 0.0)
                out_grey[dest[p]] = sky[0] + (sky[1] - sky[0]) * math.sqrt(elevation)
                out_depth[dest[p]] = np.inf
                out_label[p] = _SKY
                hit_tex[b] = -1
                continue
            t = best
            label = hit if hit >= 0 else -1 - plane
            x, y, z = ox + t * rx, oy + t * ry, oz + t * rz
            footprint = t * angles[p]
            emit = 0.0
            shade = 1.0
            lx, ly = x, y
            if plane == 0:
                r_ = min(max(int((y - origin[1]) / fres), 0), floor_map.shape[0] - 1)
                c_ = min(max(int((x - origin[0]) / fres), 0), floor_map.shape[1] - 1)
                m = floor_map[r_, c_]
                tex = floor_tex[m]
                iu, iv = floor_inv[m, 0], floor_inv[m, 1]
                u, v = x * iu, -y * iv
                foot_u = footprint * iu / math.sqrt(max(-rz, 0.05))
            elif plane > 0:
                j = plane - 1
                tex = ceil_tex[j]
                iu, iv = ceil_inv[j, 0], ceil_inv[j, 1]
                u, v = x * iu, y * iv
                foot_u = footprint * iu / math.sqrt(max(rz, 0.05))
                shade = 0.8
                r_ = min(max(int((y - origin[1]) / lamp_res), 0), lamp_map.shape[0] - 1)
                c_ = min(max(int((x - origin[0]) / lamp_res), 0), lamp_map.shape[1] - 1)
                lamp = lamp_map[r_, c_] - 1
                if lamp >= 0:
                    dx, dy = x - lamp_c[lamp, 0], y - lamp_c[lamp, 1]
                    a1 = dx * lamp_ax[lamp, 0] + dy * lamp_ax[lamp, 1]
                    a2_ = -dx * lamp_ax[lamp, 1] + dy * lamp_ax[lamp, 0]
                    hu, hv = lamp_half[lamp, 0], lamp_half[lamp, 1]
                    if abs(a1) <= hu and abs(a2_) <= hv:
                        tex = lamp_tex[lamp]
                        u, v = (a1 + hu) / (2 * hu), (hv - a2_) / (2 * hv)
                        su = 2 * hu
                        foot_u = footprint / math.sqrt(max(rz, 0.05)) / su
                        emit = lamp_emit[lamp]
                        label = _LAMP - lamp
            elif hit < nq:
                tex = qtex[hit]
                iu, iv, u0, v0 = quad_inv[hit, 0], quad_inv[hit, 1], quv[hit, 2], quv[hit, 3]
                u, v = (hs - u0) * iu, (v0 - z) * iv
                cos_i = abs(rx * qn[hit, 0] + ry * qn[hit, 1])
                foot_u = footprint * iu / math.sqrt(max(cos_i, 0.05))
                shade, emit = qshade[hit], qemit[hit]
                lx, ly = x + 0.15 * qn[hit, 0], y + 0.15 * qn[hit, 1]
            elif hit < nq + nf:
                f = hit - nq
                tex = ftex[f]
                iu, iv, u0, v0 = flat_inv[f, 0], flat_inv[f, 1], fuv[f, 2], fuv[f, 3]
                dx, dy = x - fc[f, 0], y - fc[f, 1]
                a1 = dx * fax[f, 0] + dy * fax[f, 1]
                a2_ = -dx * fax[f, 1] + dy * fax[f, 0]
                u, v = (a1 - u0) * iu, (v0 - a2_) * iv
                foot_u = footprint * iu / math.sqrt(max(abs(rz), 0.05))
                shade = 1.0 if fup[f] > 0 else 0.5
            elif hit < nq + nf + nc:
                c = hit - nq - nf
                tex = ctex[c]
                su, sv = cuv[c, 0], cuv[c, 1]
                dx, dy = x - cc[c, 0], y - cc[c, 1]
                u = (math.atan2(dy, dx) + math.pi) * cr[c] / su
                v = -z / sv
                nx, ny = dx / cr[c], dy / cr[c]
                foot_u = footprint / math.sqrt(max(abs(rx * nx + ry * ny), 0.05)) / su
                shade = 0.55 + 0.5 * max(0.0, nx * sun_w[0] + ny * sun_w[1])
                lx, ly = x + 0.15 * nx, y + 0.15 * ny
            else:
                s_ = hit - nq - nf - nc
                tex = stex[s_]
                su, sv = suv[s_, 0], suv[s_, 1]
                dx, dy, dz = x - sc[s_, 0], y - sc[s_, 1], z - sc[s_, 2]
                r_s = sr[s_]
                u = (math.atan2(dy, dx) + math.pi) * r_s / su
                v = (r_s - dz) / sv
                cos_i = abs(rx * dx + ry * dy + rz * dz) / r_s
                foot_u = footprint / math.sqrt(max(cos_i, 0.05)) / su
                sun = max(0.0, (dx * sun_w[0] + dy * sun_w[1]) / r_s)
                shade = 0.45 + 0.35 * dz / r_s + 0.35 * sun
            hit_tex[b], hit_surface[b] = tex, label
            hit_uv[b, 0], hit_uv[b, 1], hit_foot[b] = u, v, foot_u
            if emit > 0.0:
                hit_scale[b] = emit * grey_scale
            else:
                hit_scale[b] = shade * _light(lvalues, lorigin, inv_lres, lx, ly) * grey_scale
            out_depth[dest[p]] = t
            out_label[p] = label
        for b in range(count):
            tex = hit_tex[b]
            if tex >= 0:
                albedo = _sample(texels, levels, level_count, wraps, tex, hit_uv[b, 0],
                                 hit_uv[b, 1], hit_foot[b], hit_surface[b])
                out_grey[dest[first + b]] = albedo * hit_scale[b]


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def trace(pixels, neighbours, rays_c, pix_wedge, pix_angle, sub_c, sub_wedge_c, R, o, start, ids,
          quads, flats, cyls, sphs, planes, lamps, textures, light, sky, sun_w, grey_scale, work,
          out_grey, out_depth):
    """Shade every pixel (step 2 of the module docstring), edges anti-aliased.

    First one ray through each pixel's centre. Then each pixel whose surface label
    differs from a neighbour's (an edge between two surfaces) is shaded again as the
    mean of :data:`_AA` x :data:`_AA` rays on a regular grid inside the pixel (their
    bearings interpolated from the neighbours', to second order: :func:`sub_rays`,
    once per camera), so edges fall at sub-pixel positions as a real sensor
    integrates them.

    Args:
        pixels: (P,) flat indices of the valid pixels in the output images.
        neighbours: (P, 4) int32 the valid pixels' indices (into ``pixels``) of their
            right, lower, left and upper neighbours; all four -1 where one of them is
            not valid (such a pixel is never anti-aliased). Fixed for a camera.
        rays_c: (P, 3) unit bearings of the valid pixels, camera frame.
        pix_wedge: (P,) wedge of each pixel's azimuth in the robot frame.
        pix_angle: (P,) angular size of each pixel, rad.
        sub_c, sub_wedge_c: :func:`sub_rays` of the pixels (camera frame, their wedges).
        R: (3, 3) camera-to-world rotation; o: (3,) optical centre, world frame, m.
        start, ids: the wedges' candidates (:func:`bin_primitives`).
        quads, flats, cyls, sphs, planes, lamps: :class:`sim.surfaces.Scene`'s arrays.
        textures: (texels, levels, level_count, wraps) of the atlas.
        light: (values, origin, res) of the light map.
        sky: (horizon, zenith) grey; sun_w: (2,) unit direction to the sun on the plan.
        grey_scale: grey of a 128-albedo surface under light 1, divided by 128.
        work: two (P,) int32 scratch arrays (the pixels' labels, the edge pixels),
            reused from frame to frame (no page faults on fresh memory every frame).
        out_grey, out_depth: (H * W,) float32 outputs, written at ``pixels``: grey (may
            exceed 255: lamps, sky) and distance along the ray, m (inf: sky).
    """
    n = rays_c.shape[0]
    lab, edges = work
    shade_rays(rays_c, R, pix_wedge, pix_angle, o, start, ids, quads, flats, cyls, sphs, planes,
               lamps, textures, light, sky, sun_w, grey_scale, pixels, out_grey, out_depth, lab)
    # Edge pixels: those whose four neighbours are all valid and not all of their label.
    count = 0
    for p in range(n):
        right = neighbours[p, 0]
        if right < 0:
            continue
        c = lab[p]
        if (lab[right] != c or lab[neighbours[p, 1]] != c or lab[neighbours[p, 2]] != c
                or lab[neighbours[p, 3]] != c):
            edges[count] = p
            count += 1
    samples = _AA * _AA
    sub = np.empty((count * samples, 3))
    sub_wedge = np.empty(count * samples, np.int64)
    sub_angle = np.empty(count * samples)
    owner = np.empty(count, np.int64)
    m = 0
    for e in range(count):
        p = edges[e]
        owner[e] = pixels[p]
        for i in range(samples):
            for j in range(3):
                sub[m, j] = sub_c[p, i, j]
            sub_wedge[m] = sub_wedge_c[p, i]
            sub_angle[m] = pix_angle[p] / _AA
            m += 1
    sub_grey = np.empty(m, np.float32)
    sub_depth = np.empty(m, np.float32)
    sub_label = np.empty(m, np.int32)
    shade_rays(sub, R, sub_wedge, sub_angle, o, start, ids, quads, flats, cyls, sphs, planes,
               lamps, textures, light, sky, sun_w, grey_scale, np.arange(m), sub_grey,
               sub_depth, sub_label)
    for j in range(count):
        total = 0.0
        for i in range(samples):
            total += min(sub_grey[j * samples + i], 400.0)
        out_grey[owner[j]] = total / samples


def sub_rays(rays_c, neighbours, R_base_cam, wedges):
    """The anti-aliasing rays of each pixel (:func:`trace`), once per camera.

    Args:
        rays_c: (P, 3) unit bearings of the valid pixels, camera frame.
        neighbours: (P, 4) as :func:`trace` takes them.
        R_base_cam: (3, 3) camera-to-robot rotation (the wedges are azimuths there).
        wedges: the number of wedges.

    Returns:
        sub_c: (P, _AA * _AA, 3) float64 unit bearings on a regular grid inside each
            pixel, camera frame: interpolated from the pixel's and its neighbours'
            (zero where the pixel has no four neighbours).
        sub_wedge: (P, _AA * _AA) int64 their wedges.
    """
    n = rays_c.shape[0]
    samples = _AA * _AA
    sub = np.zeros((n, samples, 3))
    ok = neighbours[:, 0] >= 0
    for i in range(samples):
        sx = ((i % _AA) + 0.5) / _AA - 0.5
        sy = ((i // _AA) + 0.5) / _AA - 0.5
        hx = neighbours[ok, 0] if sx > 0 else neighbours[ok, 2]
        hy = neighbours[ok, 1] if sy > 0 else neighbours[ok, 3]
        b = rays_c[ok]
        ray = b + abs(sx) * (rays_c[hx] - b) + abs(sy) * (rays_c[hy] - b)
        sub[ok, i] = ray / np.linalg.norm(ray, axis=1)[:, None]
    base = sub @ R_base_cam.T
    azimuth = np.arctan2(base[..., 1], base[..., 0])
    wedge = np.floor((azimuth + math.pi) / (2.0 * math.pi / wedges)).astype(np.int64)
    return sub, np.clip(wedge, 0, wedges - 1)
