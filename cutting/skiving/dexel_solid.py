"""The solid of a dexel workpiece: each tooth space's removed region as a closed mesh from the dexel end points,
taken from the blank by manifold3d in one batch boolean.

A tooth space's fans (:mod:`cutting.skiving.dexel_lines`) see the cut surface from their centres C: in each slice the
space's air is the star-shaped polygon C, P_0, ..., P_n (P_i the end point of ray i: the start of the material that
holds the gear body). Lofting the slices' polygons gives a closed tube: the surface quads between neighbouring rays
and slices, the two outer rays' walls down to C, and caps beyond the end faces (the face slices copied out along
the helix, so that the tube cuts the faces cleanly). Rays whose material was not cut (the tooth lands) are drawn
back into the air, so the tube does not graze the blank's cylinder. The gear is the blank minus every space's
tube: between its end points the mesh is linear, so it lies within the chord of the ray and slice spacing of the
exact surface (plus the feed marks between slices); the measurement probes the exact surface itself.

For pictures of the stock while it is cut (the recording's snapshots) :func:`stock_mesh` closes the same ray ends
into one surface without a boolean: per slice the fans' end points make one loop round the gear (neighbouring fans
meet on the tooth centre planes), lofted from slice to slice and capped at the faces (to the axis; a ring gear's
loop to its rim). Milliseconds where the solid takes a second; its volume is the solid's within 0.002 % on the
default job.
"""

from __future__ import annotations

import manifold3d as mf
import numpy as np

from cutting.skiving.dexel_lines import DexelLines
from cutting.skiving.solids import blank

#: uncut rays (tooth lands) end this far [mn] before the blank
LAND_PULLBACK = 0.05
#: the tube reaches this far [mn] beyond each end face
FACE_OVERRUN = 0.5


def tube_ends(lines: DexelLines, lo: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, int]:
    """Per line the distance from its fan's centre to the tube's vertex, from the material intervals (their starts
    ``lo`` (lines, pieces), count ``n``), and how many land rays the cut touched.

    A profile ray (between the tip corners) ends where the material that holds the gear body starts: its last
    interval (a fin or burr inside the space before it is left out of the solid; its end if the cut took all of
    it). A land ray meets the tooth's top at a grazing angle and holds a short chord of the tooth tip: it ends at
    its first material, and where the cut took all of that chord (a cutter grazing the tips at a face) it is drawn
    as uncut: the fan cannot draw a tip cut through to the tooth's centre plane without cutting the tooth beside
    it. Uncut ends are drawn back into the air."""
    ln = lines
    rows = np.arange(len(n))
    land = np.tile(ln.land, ln.spaces * ln.slices)
    entry = np.tile(ln.ray_entry, ln.spaces * ln.slices)
    length = np.tile(ln.ray_length, ln.spaces * ln.slices)
    last = np.where(n > 0, lo[rows, np.maximum(n - 1, 0)], length)
    first = np.where(n > 0, lo[:, 0], entry)
    rho = np.where(land, first, last)
    touched = land & ((n == 0) | (first > entry + 1e-9) | (n > 1)) & (length > entry + 1e-9)
    uncut = rho <= entry + 1e-9
    rho = np.where(uncut | (land & (n == 0)), entry - LAND_PULLBACK * ln.gear.mn, rho)
    return rho, int(touched.sum())


def space_tube(lines: DexelLines, ends: np.ndarray, space: int) -> tuple[np.ndarray, np.ndarray]:
    """The closed tube of ``space`` (vertices (m, 3), triangles (k, 3), outward) from the per-line tube ends
    (:func:`tube_ends`, line order)."""
    ln = lines
    g = ln.gear
    rays, slices = ln.rays, ln.slices
    rho = ends.reshape(ln.spaces, slices, rays)[space]
    over = FACE_OVERRUN * g.mn
    z = np.r_[ln.z[0] - over, ln.z, ln.z[-1] + over]
    rho = np.concatenate([rho[:1], rho, rho[-1:]])
    ang = ln.frame_angle(space, z)  # (S,)
    c, s = np.cos(ang), np.sin(ang)
    # local (space frame) points of each slice: C then the ray ends
    lx = np.concatenate([np.full((len(z), 1), ln.centre_radius), ln.centre_radius + rho * ln.ray_u[None, :, 0]], 1)
    ly = np.concatenate([np.zeros((len(z), 1)), rho * ln.ray_u[None, :, 1]], 1)
    verts = np.stack(
        [c[:, None] * lx - s[:, None] * ly, s[:, None] * lx + c[:, None] * ly, np.broadcast_to(z[:, None], lx.shape)],
        axis=-1,
    ).reshape(-1, 3)
    per = rays + 1
    n_s = len(z)
    jj, ii = np.meshgrid(np.arange(n_s - 1), np.arange(rays - 1), indexing="ij")
    jj, ii = jj.ravel(), ii.ravel()
    a = jj * per + 1 + ii  # (j, i)
    b, cc, d = a + 1, a + per + 1, a + per  # (j, i+1), (j+1, i+1), (j+1, i)
    quads = [np.stack([a, b, cc], 1), np.stack([a, cc, d], 1)]
    j = np.arange(n_s - 1)
    centre, centre_next = j * per, (j + 1) * per
    first, first_next = j * per + 1, (j + 1) * per + 1
    last, last_next = j * per + rays, (j + 1) * per + rays
    # the polygon C, P_0 .. P_n lofted: the walls C -> P_0 and P_n -> C like the surface quads P_i -> P_i+1
    walls = [np.stack([centre, first, first_next], 1), np.stack([centre, first_next, centre_next], 1)]
    walls += [np.stack([last, centre, centre_next], 1), np.stack([last, centre_next, last_next], 1)]
    i = np.arange(rays - 1)
    top = (n_s - 1) * per
    caps = [
        np.stack([np.zeros(rays - 1, int), 2 + i, 1 + i], 1),
        np.stack([np.full(rays - 1, top), top + 1 + i, top + 2 + i], 1),
    ]
    tris = np.concatenate(quads + walls + caps).astype(np.int64)
    if _signed_volume(verts, tris) < 0:
        tris = tris[:, ::-1]
    return verts, tris


def _signed_volume(verts: np.ndarray, tris: np.ndarray) -> float:
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6)


def removed_region(lines: DexelLines, ends: np.ndarray) -> list[mf.Manifold]:
    """Every space's tube as a manifold solid (checked)."""
    out = []
    for k in range(lines.spaces):
        verts, tris = space_tube(lines, ends, k)
        solid = mf.Manifold(mf.Mesh64(vert_properties=verts, tri_verts=tris.astype(np.uint64)))
        if solid.status() != mf.Error.NoError:
            raise RuntimeError(f"the dexel tube of tooth space {k} is not a closed solid ({solid.status()})")
        out.append(solid)
    return out


def dexel_solid(workpiece, rim: float | None = None) -> tuple[mf.Manifold, int]:
    """The gear of a dexel workpiece (on a gear's fans): the blank minus every tooth space's tube, in one batch
    boolean (evaluated here); and the land rays the cut touched (:func:`tube_ends`)."""
    lines = workpiece.lines
    ends, touched = tube_ends(lines, workpiece.mat_lo, workpiece.mat_n)
    solid = mf.Manifold.batch_boolean([blank(lines.gear, rim), *removed_region(lines, ends)], mf.OpType.Subtract)
    solid.status()
    return solid, touched


def stock_mesh(workpiece, ray_stride: int = 1, slice_stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The stock of a dexel workpiece (on a gear's fans) as one closed mesh (vertices (n, 3) [mm], triangles (m, 3),
    outward), from the same ray ends as :func:`dexel_solid` (:func:`tube_ends`) and no boolean: per slice one loop
    of every fan's ray ends in turn, clamped to the blank (an uncut land drawn back into the air lies on the tip
    circle), lofted between slices; the end faces fanned to the axis (a ring gear: joined to its rim). Every
    ``ray_stride``-th ray and ``slice_stride``-th slice (a lighter picture; the first and last of each, the tip
    corners' rays and the end faces kept). The topology depends only on the lines and the strides: every mesh of a
    workpiece has the same triangles."""
    ln = workpiece.lines
    g = ln.gear
    rho = tube_ends(ln, workpiece.mat_lo, workpiece.mat_n)[0].reshape(ln.spaces, ln.slices, ln.rays)
    rays = np.zeros(ln.rays, bool)
    rays[::ray_stride] = True
    rays[[0, -1]] = True
    rays |= np.r_[False, np.diff(ln.land.astype(int)) != 0] | np.r_[np.diff(ln.land.astype(int)) != 0, False]
    slices = np.zeros(ln.slices, bool)
    slices[::slice_stride] = True
    slices[[0, -1]] = True
    rho, z = rho[:, slices][:, :, rays], ln.z[slices]
    u = ln.ray_u[rays]
    lx, ly = ln.centre_radius + rho * u[:, 0], rho * u[:, 1]
    ang = ln.frame_angle(np.arange(ln.spaces)[:, None, None], z[None, :, None])
    x = (np.cos(ang) * lx - np.sin(ang) * ly).transpose(1, 0, 2).reshape(len(z), -1)  # (slices, loop)
    y = (np.sin(ang) * lx + np.cos(ang) * ly).transpose(1, 0, 2).reshape(len(z), -1)
    r = np.hypot(x, y)
    outside = r < g.tip_radius if g.internal else r > g.tip_radius
    scale = np.where(outside, g.tip_radius / np.maximum(r, 1e-12), 1.0)
    x, y = x * scale, y * scale
    n_s, n = x.shape
    verts = np.stack([x, y, np.broadcast_to(z[:, None], x.shape)], -1).reshape(-1, 3)
    j, i = (a.ravel() for a in np.meshgrid(np.arange(n_s - 1), np.arange(n), indexing="ij"))
    a, b = j * n + i, j * n + (i + 1) % n
    tris = [np.stack([a, b, b + n], 1), np.stack([a, b + n, a + n], 1)]
    ring = np.arange(n)
    bottom, top = ring, (n_s - 1) * n + ring
    if g.internal:  # the rim: the same loop's angles at the rim radius, its wall and the two annular faces
        o = len(verts)
        theta = np.arctan2(y, x)
        rim = np.stack([ln.rim_radius * np.cos(theta), ln.rim_radius * np.sin(theta), verts[:, 2].reshape(x.shape)])
        verts = np.concatenate([verts, rim.transpose(1, 2, 0).reshape(-1, 3)])
        tris += [np.stack([o + a, o + b + n, o + b], 1), np.stack([o + a, o + a + n, o + b + n], 1)]
        b_next, t_next = (ring + 1) % n, (n_s - 1) * n + (ring + 1) % n  # each loop's next point
        tris += [np.stack([bottom, o + bottom, b_next], 1), np.stack([b_next, o + bottom, o + b_next], 1)]
        tris += [np.stack([top, t_next, o + top], 1), np.stack([t_next, o + t_next, o + top], 1)]
    else:  # fans from the axis at each end face
        c = len(verts)
        verts = np.concatenate([verts, [[0.0, 0.0, z[0]], [0.0, 0.0, z[-1]]]])
        tris += [np.stack([np.full(n, c), (bottom + 1) % n, bottom], 1)]
        tris += [np.stack([np.full(n, c + 1), top, (n_s - 1) * n + (ring + 1) % n], 1)]
    tris = np.concatenate(tris).astype(np.int64)
    if _signed_volume(verts, tris) < 0:
        tris = tris[:, ::-1]
    return verts, tris
