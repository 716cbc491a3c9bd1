"""Submerged volume and centre of buoyancy of floes by triangle clipping (paper §2.3).

Each floe is a closed, outward mesh given relative to its centre of mass. Its pose in the
vertical is heave z_c (centre of mass above the water plane z = 0, m), roll phi (about x)
and pitch theta (about y), applied as R = R_y(theta) R_x(phi); yaw does not change what is
under water and is left out (coordinates are in the floe's yaw-aligned frame).

Every triangle is classified by how many vertices lie below the water plane, the paper's
types: all three under (type 0, kept), none under (type 2, dropped), or partly under
(type 1, split at the waterline: one vertex under -> one triangle, two under -> two
triangles). The kept pieces with the origin on the water plane form signed tetrahedra
(det(a, b, c) / 6, sign from the triangle's orientation against the water normal); the
waterline cap lies in the plane z = 0 and so adds nothing. Their sum is the submerged
volume and their volume-weighted centroids give the centre of buoyancy.

``submerged_volume_centre`` is the numba kernel (parallel over floes);
``submerged_volume_centre_reference`` is the plain numpy version it is tested against.
"""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, inline="always")
def _rotate(p0, p1, p2, cr, sr, cp, sp, zc):
    """R_y(pitch) R_x(roll) p + (0, 0, zc)."""
    y1 = cr * p1 - sr * p2
    z1 = sr * p1 + cr * p2
    return cp * p0 + sp * z1, y1, -sp * p0 + cp * z1 + zc


@numba.njit(cache=True, inline="always")
def _cut(ax, ay, az, bx, by, bz):
    """Point where segment a-b crosses z = 0."""
    t = az / (az - bz)
    return ax + t * (bx - ax), ay + t * (by - ay), 0.0


@numba.njit(cache=True, inline="always")
def _tet(ax, ay, az, bx, by, bz, cx, cy, cz, acc):
    """Add 6 x signed volume and 24 x first moment of the tetrahedron (0, a, b, c)."""
    d = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    acc[0] += d
    acc[1] += d * (ax + bx + cx)
    acc[2] += d * (ay + by + cy)
    acc[3] += d * (az + bz + cz)


@numba.njit(cache=True)
def _floe_submerged(tris, t0, t1, zc, roll, pitch, acc):
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    acc[:] = 0.0
    for t in range(t0, t1):
        ax, ay, az = _rotate(tris[t, 0, 0], tris[t, 0, 1], tris[t, 0, 2], cr, sr, cp, sp, zc)
        bx, by, bz = _rotate(tris[t, 1, 0], tris[t, 1, 1], tris[t, 1, 2], cr, sr, cp, sp, zc)
        cx, cy, cz = _rotate(tris[t, 2, 0], tris[t, 2, 1], tris[t, 2, 2], cr, sr, cp, sp, zc)
        under = (az < 0.0) + (bz < 0.0) + (cz < 0.0)
        if under == 0:
            continue
        if under == 3:
            _tet(ax, ay, az, bx, by, bz, cx, cy, cz, acc)
            continue
        # rotate the vertex order (keeping orientation) so that vertex a is the odd one out
        if (bz < 0.0) != (az < 0.0) and (bz < 0.0) != (cz < 0.0):
            ax, ay, az, bx, by, bz, cx, cy, cz = bx, by, bz, cx, cy, cz, ax, ay, az
        elif (cz < 0.0) != (az < 0.0) and (cz < 0.0) != (bz < 0.0):
            ax, ay, az, bx, by, bz, cx, cy, cz = cx, cy, cz, ax, ay, az, bx, by, bz
        abx, aby, abz = _cut(ax, ay, az, bx, by, bz)
        acx, acy, acz = _cut(ax, ay, az, cx, cy, cz)
        if under == 1:  # a alone under water: one triangle a, ab, ac
            _tet(ax, ay, az, abx, aby, abz, acx, acy, acz, acc)
        else:  # b and c under water: quad ab, b, c, ac -> two triangles
            _tet(abx, aby, abz, bx, by, bz, cx, cy, cz, acc)
            _tet(abx, aby, abz, cx, cy, cz, acx, acy, acz, acc)


@numba.njit(cache=True, parallel=True)
def submerged_volume_centre(tris, tri_start, cells, zc, roll, pitch):
    """Submerged volume (n,) m3 and centre of buoyancy (n, 3) m, in the floe's yaw-aligned
    frame with the water plane at z = 0, for floes i with template cell ``cells[i]`` whose
    triangles are ``tris[tri_start[c]:tri_start[c+1]]`` ((T, 3, 3), about the centroid)."""
    n = len(cells)
    vol = np.zeros(n)
    centre = np.zeros((n, 3))
    for i in numba.prange(n):
        acc = np.zeros(4)
        c = cells[i]
        _floe_submerged(tris, tri_start[c], tri_start[c + 1], zc[i], roll[i], pitch[i], acc)
        vol[i] = acc[0] / 6.0
        if acc[0] > 0.0:
            centre[i, 0] = acc[1] / (4.0 * acc[0])
            centre[i, 1] = acc[2] / (4.0 * acc[0])
            centre[i, 2] = acc[3] / (4.0 * acc[0])
    return vol, centre


def posed_vertices(tris: np.ndarray, zc, roll, pitch) -> np.ndarray:
    """Triangles (T, 3, 3) of one floe in its yaw-aligned frame at the given vertical pose."""
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    return tris @ (ry @ rx).T + np.array([0.0, 0.0, zc])


def submerged_volume_centre_reference(tris, tri_start, cells, zc, roll, pitch):
    """Plain numpy version of ``submerged_volume_centre``: all triangles at once, the split
    cases enumerated explicitly."""
    n = len(cells)
    counts = tri_start[cells + 1] - tri_start[cells]
    idx = np.concatenate([np.arange(tri_start[c], tri_start[c + 1]) for c in cells]) if n else np.zeros(0, int)
    owner = np.repeat(np.arange(n), counts)
    cr, sr = np.cos(roll)[owner], np.sin(roll)[owner]
    cp, sp = np.cos(pitch)[owner], np.sin(pitch)[owner]
    p = tris[idx]
    y1 = cr[:, None] * p[..., 1] - sr[:, None] * p[..., 2]
    z1 = sr[:, None] * p[..., 1] + cr[:, None] * p[..., 2]
    v = np.stack([cp[:, None] * p[..., 0] + sp[:, None] * z1, y1,
                  -sp[:, None] * p[..., 0] + cp[:, None] * z1 + zc[owner][:, None]], axis=-1)
    below = v[..., 2] < 0.0
    under = below.sum(axis=1)
    pieces, piece_owner = [], []
    pieces.append(v[under == 3])
    piece_owner.append(owner[under == 3])
    for k in (1, 2):
        sel = np.nonzero(under == k)[0]
        vs, bs = v[sel], below[sel]
        odd = np.where(bs.sum(axis=1) == 1, np.argmax(bs, axis=1), np.argmax(~bs, axis=1))
        order = (odd[:, None] + np.arange(3)[None, :]) % 3  # cyclic: keeps orientation
        vs = np.take_along_axis(vs, order[..., None], axis=1)
        a, b, c = vs[:, 0], vs[:, 1], vs[:, 2]
        ab = a + (a[:, 2] / (a[:, 2] - b[:, 2]))[:, None] * (b - a)
        ac = a + (a[:, 2] / (a[:, 2] - c[:, 2]))[:, None] * (c - a)
        if k == 1:
            pieces.append(np.stack([a, ab, ac], axis=1))
            piece_owner.append(owner[sel])
        else:
            pieces.append(np.stack([ab, b, c], axis=1))
            pieces.append(np.stack([ab, c, ac], axis=1))
            piece_owner += [owner[sel], owner[sel]]
    tri_p = np.concatenate(pieces)
    own = np.concatenate(piece_owner)
    det = np.einsum("ij,ij->i", tri_p[:, 0], np.cross(tri_p[:, 1], tri_p[:, 2]))
    vol6 = np.bincount(own, det, minlength=n)
    moment = np.stack([np.bincount(own, det * tri_p[:, :, j].sum(axis=1), minlength=n) for j in range(3)], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        centre = np.where(vol6[:, None] > 0, moment / (4.0 * vol6[:, None]), 0.0)
    return vol6 / 6.0, centre
