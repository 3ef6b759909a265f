"""The numpy raycaster: a first-person RGB-D image of a storey and the boxes of the visible features.

Walls are vertical and the camera has no pitch or roll, so one ray per image column finds the
wall (and the nearest clutter box); each pixel of the column is then wall, feature, decoration,
clutter, floor or ceiling depending on the height at which its ray meets that wall. Everything
is vectorised over columns and pixels: about 100-200 frames/s at 320x240 on one core.

Depth is the optical z of Eq. 1 (metres along the optical axis); 0 where nothing is within
``camera.max_range``. Boxes are ``[u1, v1, u2, v2]`` in pixels around the visible pixels of a
feature (occluded and out-of-image parts excluded), with the visible fraction of its full area.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.raycast import ray_segment_params
from initcli.detector.synth.look import FeatureLooks, Look, default_look
from initcli.detector.synth.paint import clutter_colours, decoration_colours, feature_colours, texture
from initcli.detector.synth.scene import Camera, Panels, Scene

__all__ = ["NEAR", "PANEL_TOLERANCE", "View", "VisibleFeature", "cast_rays", "render_view"]

NEAR = 0.05  # m: nothing is rendered closer than this
PANEL_TOLERANCE = 0.08  # m: a wall hit this close to a panel's plane is on the panel


@dataclass(frozen=True)
class VisibleFeature:
    """A feature seen in a view: its box around the visible pixels and how much of it is visible."""

    index: int  # into Scene.features
    feature_id: str
    class_name: str
    box: tuple[float, float, float, float]  # u1, v1, u2, v2 (pixels, pixel edges)
    visible_fraction: float  # visible pixels / area of the whole projected rectangle
    in_image_fraction: float  # part of the projected rectangle inside the image
    pixels: int
    distance: float  # optical depth of the feature's centre, m


@dataclass
class View:
    rgb: np.ndarray  # (H, W, 3) uint8, RGB
    depth: np.ndarray  # (H, W) float32 metres, 0 = no return
    ids: np.ndarray  # (H, W) int16 feature index, -1 elsewhere
    features: list[VisibleFeature]
    camera: Camera
    pose: tuple[float, float, float]

    @property
    def bgr(self) -> np.ndarray:
        """The image in OpenCV's channel order (what :meth:`Detector.detect` takes)."""
        return np.ascontiguousarray(self.rgb[..., ::-1])


def cast_rays(
    origin: np.ndarray, dirs: np.ndarray, segs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays ``origin + t * dirs`` (W, 2) against segments (S, 4): all t (W, S) (inf = miss), the
    position s along each segment and the hits (:func:`initcli.core.geometry.raycast.ray_segment_params`;
    a hit is ``t > 1e-6`` and ``s`` in [0, 1] give or take 1e-9)."""
    a = segs[:, 0:2]
    e = segs[:, 2:4] - a
    ao = a - origin
    _, t, s = ray_segment_params(
        ao[None, :, 0], ao[None, :, 1], dirs[:, 0:1], dirs[:, 1:2], e[None, :, 0], e[None, :, 1]
    )
    hit = (t > 1e-6) & (s >= -1e-9) & (s <= 1.0 + 1e-9)
    return np.where(hit, t, np.inf), s, hit


def _segment_distance(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    a, b = segs[:, 0:2], segs[:, 2:4]
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12)
    s = np.clip(np.einsum("ij,ij->i", p - a, ab) / L2, 0.0, 1.0)
    c = a + ab * s[:, None]
    return np.hypot(c[:, 0] - p[0], c[:, 1] - p[1])


def _visible_walls(scene: Scene, cam: np.ndarray, fwd: np.ndarray, max_range: float) -> np.ndarray:
    """Indices of wall segments that can be hit: in range, in front, facing the camera."""
    w = scene.walls
    if len(w) == 0:
        return np.zeros(0, dtype=int)
    e = w[:, 2:4] - w[:, 0:2]
    normal = np.column_stack([e[:, 1], -e[:, 0]])
    facing = scene.two_sided | (np.einsum("ij,ij->i", cam - w[:, 0:2], normal) > 0)
    front = ((w[:, 0:2] - cam) @ fwd > 0) | ((w[:, 2:4] - cam) @ fwd > 0)
    near = _segment_distance(cam, w) < max_range
    return np.flatnonzero(facing & front & near)


def _panel_lookup(
    panels: Panels,
    cam: np.ndarray,
    hit: np.ndarray,
    dirs: np.ndarray,
    hit_normal: np.ndarray,
    max_range: float,
) -> tuple[np.ndarray, np.ndarray]:
    """For each column's wall hit: the panel it lies on (-1 none) and the across coordinate a (m)."""
    n_cols = len(hit)
    which = np.full(n_cols, -1, dtype=int)
    across = np.zeros(n_cols)
    if len(panels) == 0:
        return which, across
    c, n, t = panels.centre, panels.normal, panels.tangent
    rel_cam = cam - c
    cand = np.flatnonzero((np.einsum("ij,ij->i", rel_cam, n) > 0) & (np.hypot(*rel_cam.T) < max_range + 2.0))
    if len(cand) == 0:
        return which, across
    c, n, t, hw = c[cand], n[cand], t[cand], panels.half_width[cand]
    rel = hit[:, None, :] - c[None, :, :]
    a = rel[..., 0] * t[None, :, 0] + rel[..., 1] * t[None, :, 1]
    b = rel[..., 0] * n[None, :, 0] + rel[..., 1] * n[None, :, 1]
    parallel = np.abs(hit_normal @ n.T) > 0.9
    ok = (np.abs(b) < PANEL_TOLERANCE) & (np.abs(a) <= hw[None, :]) & parallel
    anyok = ok.any(axis=1)
    j = np.argmax(ok, axis=1)
    which[anyok] = cand[j[anyok]]
    across[anyok] = a[anyok, j[anyok]]
    return which, across


def _projected_rect(
    cam: np.ndarray,
    fwd: np.ndarray,
    right: np.ndarray,
    centre: np.ndarray,
    tangent: np.ndarray,
    half_width: float,
    height: float,
    camera: Camera,
) -> tuple[float, float, float]:
    """Area of a feature's whole projected rectangle, the part inside the image, depth of its centre."""
    ends = np.array([centre - tangent * half_width, centre + tangent * half_width]) - cam
    z = ends @ fwd
    x = ends @ right
    depth = float((centre - cam) @ fwd)
    if z.max() <= NEAR:
        return 0.0, 0.0, depth
    if z.min() < NEAR:  # clip the rectangle at the near plane
        k = (NEAR - z[0]) / (z[1] - z[0])
        xi = x[0] + k * (x[1] - x[0])
        if z[0] < NEAR:
            z[0], x[0] = NEAR, xi
        else:
            z[1], x[1] = NEAR, xi
    u = camera.cx + camera.fx * x / z
    top = camera.cy + camera.fy * (camera.z - height) / z
    bot = camera.cy + camera.fy * camera.z / z
    full = abs(u[1] - u[0]) * float(np.mean(bot - top))
    lo, hi = max(min(u), 0.0), min(max(u), float(camera.width))
    if full <= 0 or hi <= lo:
        return full, 0.0, depth
    cols = np.arange(math.floor(lo), math.ceil(hi)) + 0.5
    cols = cols[(cols >= lo) & (cols <= hi)]
    if len(cols) == 0:
        return full, 0.0, depth
    k = (cols - u[0]) / (u[1] - u[0])
    tt = top[0] + k * (top[1] - top[0])
    bb = bot[0] + k * (bot[1] - bot[0])
    inside = np.clip(bb, 0, camera.height) - np.clip(tt, 0, camera.height)
    return full, float(np.clip(inside, 0, None).sum()), depth


def render_view(
    scene: Scene, pose_xy_yaw: tuple[float, float, float], camera: Camera, look: Look | None = None
) -> View:
    """Render the camera image at a camera pose (x, y, yaw) in the BIM frame.

    A pure function of its arguments. ``look`` defaults to :func:`default_look` (what the
    simulator uses); pass :func:`random_look` for domain randomisation.
    """
    x0, y0, yaw = (float(v) for v in pose_xy_yaw)
    if look is None:
        look = default_look(scene.feature_panels.kind, scene.class_names)
    fl = look.features or default_look(scene.feature_panels.kind, scene.class_names).features
    assert fl is not None
    rays = _Rays.of(x0, y0, yaw, camera)
    walls = _cast_walls(scene, rays, camera.max_range)
    light = np.array([math.cos(look.light_angle), math.sin(look.light_angle)])
    px = _Pixels.of(rays, walls, camera.z, scene.ceiling)
    rgb = np.empty((camera.height, camera.width, 3), dtype=np.float64)
    ids = _paint_walls(rgb, px, scene, look, fl, walls, light)
    _paint_floor(rgb, px, rays, look)
    _paint_ceiling(rgb, px, rays, look)
    _paint_clutter(rgb, px, ids, scene, look, rays, walls.z, light, camera)
    image, depth = _fade(rgb, px, look, camera.max_range)
    return View(
        image,
        depth.astype(np.float32),
        ids,
        _visible_features(scene, ids, rays.cam, rays.fwd, rays.right, camera),
        camera,
        (x0, y0, yaw),
    )


@dataclass(frozen=True)
class _Rays:
    """The camera's rays in the plan: one per image column, and each image row's vertical slope."""

    cam: np.ndarray  # (2,) camera position
    fwd: np.ndarray  # (2,) optical axis
    right: np.ndarray  # (2,) image x axis
    dirs: np.ndarray  # (W, 2) column rays, forward component 1: t is the optical depth
    rv: np.ndarray  # (H,) row slopes: a row's ray falls rv metres per metre of depth

    @staticmethod
    def of(x0: float, y0: float, yaw: float, camera: Camera) -> _Rays:
        fwd = np.array([math.cos(yaw), math.sin(yaw)])
        right = np.array([fwd[1], -fwd[0]])
        xn = (np.arange(camera.width) + 0.5 - camera.cx) / camera.fx
        dirs = fwd[None, :] + xn[:, None] * right[None, :]
        rv = ((np.arange(camera.height) + 0.5 - camera.cy) / camera.fy).astype(np.float64)
        return _Rays(np.array([x0, y0]), fwd, right, dirs, rv)


@dataclass(frozen=True)
class _WallHits:
    """Where each column's ray meets the walls, and the feature or decoration panel it lies on."""

    z: np.ndarray  # (W,) optical depth of the hit; max_range where no wall is in range
    void: np.ndarray  # (W,) no wall within range
    normal: np.ndarray  # (W, 2) the wall's normal, towards the camera
    tex_u: np.ndarray  # (W,) texture coordinate along the walls, m
    feature: np.ndarray  # (W,) feature panel index, -1 none
    feature_a: np.ndarray  # (W,) across coordinate on that panel, m
    decoration: np.ndarray  # (W,) decoration index, -1 none
    decoration_a: np.ndarray  # (W,) across coordinate on that decoration, m


def _cast_walls(scene: Scene, rays: _Rays, max_range: float) -> _WallHits:
    """One ray per column against the walls that can be hit."""
    cam, dirs = rays.cam, rays.dirs
    n_cols = len(dirs)
    wall_ids = _visible_walls(scene, cam, rays.fwd, max_range)
    if len(wall_ids):
        segs = scene.walls[wall_ids]
        t_all, s_all, _ = cast_rays(cam, dirs, segs)
        j = np.argmin(t_all, axis=1)
        cols = np.arange(n_cols)
        z_wall = t_all[cols, j]
        s_hit = np.clip(s_all[cols, j], 0.0, 1.0)
        seg = segs[j]
        e = seg[:, 2:4] - seg[:, 0:2]
        seg_len = np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-9)
        hit_normal = np.column_stack([e[:, 1], -e[:, 0]]) / seg_len[:, None]
        flip = np.einsum("ij,ij->i", hit_normal, dirs) > 0
        hit_normal[flip] *= -1
        tex_u = scene.wall_offset[wall_ids][j] + s_hit * seg_len
    else:
        z_wall = np.full(n_cols, np.inf)
        hit_normal = -dirs / np.hypot(dirs[:, 0], dirs[:, 1])[:, None]
        tex_u = np.zeros(n_cols)
    void_col = ~np.isfinite(z_wall) | (z_wall > max_range)
    z_wall = np.where(void_col, max_range, z_wall)
    hit = cam + dirs * z_wall[:, None]
    feat_col, feat_a = _panel_lookup(scene.feature_panels, cam, hit, dirs, hit_normal, max_range)
    feat_col[void_col] = -1
    dec_col, dec_a = _panel_lookup(scene.decorations, cam, hit, dirs, hit_normal, max_range)
    dec_col[void_col] = -1
    return _WallHits(z_wall, void_col, hit_normal, tex_u, feat_col, feat_a, dec_col, dec_a)


@dataclass(frozen=True)
class _Pixels:
    """What each pixel's ray meets first of wall, floor and ceiling (clutter aside), and how far."""

    h_wall: np.ndarray  # (H, W) height at which the pixel's ray meets the wall
    is_floor: np.ndarray  # (H, W)
    is_ceil: np.ndarray  # (H, W)
    is_wall: np.ndarray  # (H, W)
    z_floor: np.ndarray  # (H,) optical depth at which each row meets the floor (inf: never)
    z_ceil: np.ndarray  # (H,) optical depth at which each row meets the ceiling (inf: never)
    depth: np.ndarray  # (H, W) optical depth; the clutter painter writes its own into it
    void: np.ndarray  # (H, W) nothing within range; the clutter painter clears what it covers

    @staticmethod
    def of(rays: _Rays, walls: _WallHits, cz: float, ceiling: float) -> _Pixels:
        rv, z_wall = rays.rv, walls.z
        h_wall = cz - rv[:, None] * z_wall[None, :]
        is_floor = h_wall < 0
        is_ceil = h_wall > ceiling
        is_wall = ~(is_floor | is_ceil)
        with np.errstate(divide="ignore"):
            z_floor = np.where(rv > 0, cz / np.where(rv > 0, rv, 1.0), np.inf)
            z_ceil = np.where(rv < 0, (ceiling - cz) / np.where(rv < 0, -rv, 1.0), np.inf)
        depth = np.where(is_wall, z_wall[None, :], np.where(is_floor, z_floor[:, None], z_ceil[:, None]))
        void = is_wall & walls.void[None, :]
        return _Pixels(h_wall, is_floor, is_ceil, is_wall, z_floor, z_ceil, depth, void)


def _paint_walls(
    rgb: np.ndarray,
    px: _Pixels,
    scene: Scene,
    look: Look,
    fl: FeatureLooks,
    walls: _WallHits,
    light: np.ndarray,
) -> np.ndarray:
    """Paint the wall pixels (texture, skirting, features, decorations); the feature index map."""
    wr, wc = np.nonzero(px.is_wall)
    hw_ = px.h_wall[wr, wc]
    ceiling = scene.ceiling
    tex = texture(hw_ * look.wall_tex_scale, walls.tex_u[wc] * look.wall_tex_scale)
    wall_col = look.wall_rgb[None, :] * (1.0 + look.wall_tex * tex)[:, None]
    if look.skirting_h > 0:
        wall_col = np.where((hw_ < look.skirting_h)[:, None], look.skirting_rgb, wall_col)
    wall_col *= (1.0 + 0.12 * (hw_ / ceiling - 0.5))[:, None]

    ids = np.full(px.h_wall.shape, -1, dtype=np.int16)
    fidx = walls.feature[wc]
    on_feat = fidx >= 0
    if on_feat.any():
        fi = fidx[on_feat]
        hh = hw_[on_feat]
        inside = hh <= scene.feature_panels.top[fi]
        sel = np.flatnonzero(on_feat)[inside]
        fi = fi[inside]
        if len(sel):
            code = _feature_codes(scene)[fi]
            wall_col[sel] = feature_colours(
                code,
                walls.feature_a[wc[sel]],
                hw_[sel],
                scene.feature_panels.half_width[fi],
                scene.feature_panels.top[fi],
                fl,
                fi,
            )
            ids[wr[sel], wc[sel]] = fi
    didx = walls.decoration[wc]
    on_dec = (didx >= 0) & (ids[wr, wc] < 0)
    if on_dec.any():
        di = didx[on_dec]
        hh = hw_[on_dec]
        d = scene.decorations
        inside = (hh >= d.bottom[di]) & (hh <= d.top[di])
        sel = np.flatnonzero(on_dec)[inside]
        di = di[inside]
        if len(sel):
            wall_col[sel] = decoration_colours(
                d.kind[di],
                walls.decoration_a[wc[sel]],
                hw_[sel],
                d.bottom[di],
                d.top[di],
                d.half_width[di],
                d.rgb[di],
                di,
            )
    shade_col = look.ambient + look.diffuse * np.abs(walls.normal @ light)
    rgb[wr, wc] = wall_col * shade_col[wc, None]
    return ids


def _paint_floor(rgb: np.ndarray, px: _Pixels, rays: _Rays, look: Look) -> None:
    """Paint the floor pixels: checkered tiles with grout."""
    fr, fc = np.nonzero(px.is_floor)
    zf = px.z_floor[fr]
    x = rays.cam[0] + zf * rays.dirs[fc, 0]
    y = rays.cam[1] + zf * rays.dirs[fc, 1]
    tile = look.floor_tile
    gx, gy = x / tile, y / tile
    checker = ((np.floor(gx) + np.floor(gy)) % 2 == 0)[:, None]
    floor_col = np.where(checker, look.floor_rgb, look.floor_rgb2)
    floor_col = floor_col * (1.0 + look.floor_tex * texture(x * 50.0, y * 50.0))[:, None]
    if look.grout > 0:
        grout = ((gx - np.floor(gx)) < look.grout) | ((gy - np.floor(gy)) < look.grout)
        floor_col = np.where(grout[:, None], look.grout_rgb, floor_col)
    rgb[fr, fc] = floor_col * (look.ambient + 0.5 * look.diffuse)


def _paint_ceiling(rgb: np.ndarray, px: _Pixels, rays: _Rays, look: Look) -> None:
    """Paint the ceiling pixels: a tile grid and lamps."""
    cr, cc = np.nonzero(px.is_ceil)
    zc = px.z_ceil[cr]
    qx = rays.cam[0] + zc * rays.dirs[cc, 0]
    qy = rays.cam[1] + zc * rays.dirs[cc, 1]
    ceil_col = np.broadcast_to(look.ceiling_rgb, (len(cr), 3)) * 0.92
    if look.ceiling_grid > 0:
        g = look.ceiling_grid
        line = ((qx / g) % 1.0 < 0.025) | ((qy / g) % 1.0 < 0.025)
        ceil_col = np.where(line[:, None], ceil_col * 0.8, ceil_col)
    if look.lights > 0:
        s = look.lights
        lamp = ((qx / s) % 1.0 < 0.5 / s) & ((qy / s) % 1.0 < 1.2 / s)
        ceil_col = np.where(lamp[:, None], 255.0 * 1.3, ceil_col)
    rgb[cr, cc] = ceil_col * look.ambient * 1.1


def _paint_clutter(
    rgb: np.ndarray,
    px: _Pixels,
    ids: np.ndarray,
    scene: Scene,
    look: Look,
    rays: _Rays,
    z_wall: np.ndarray,
    light: np.ndarray,
    camera: Camera,
) -> None:
    """Paint the free-standing boxes and people in front of the walls: side faces and visible top
    faces (their depth into ``px.depth``; no feature behind them in ``ids``)."""
    cl = scene.clutter
    if not cl.count:
        return
    cam, rv, cz = rays.cam, rays.rv, camera.z
    near = np.flatnonzero(_segment_distance(cam, cl.segments) < camera.max_range)
    if not len(near):
        return
    t_all, _, _ = cast_rays(cam, rays.dirs, cl.segments[near])
    j = np.argmin(t_all, axis=1)
    cols = np.arange(camera.width)
    z_in = t_all[cols, j]
    has = np.isfinite(z_in) & (z_in < z_wall)
    if not has.any():
        return
    obj = cl.obj[near][j]
    same = cl.obj[near][None, :] == obj[:, None]
    z_out = np.where(same & np.isfinite(t_all), t_all, -np.inf).max(axis=1)
    top = cl.top[obj]
    h_in = cz - rv[:, None] * z_in[None, :]
    h_out = cz - rv[:, None] * z_out[None, :]
    side = has[None, :] & (h_in >= 0) & (h_in <= top[None, :])
    lid = has[None, :] & (h_in > top[None, :]) & (h_out <= top[None, :]) & (rv[:, None] > 0)
    seg = cl.segments[near][j]
    e = seg[:, 2:4] - seg[:, 0:2]
    nrm = np.column_stack([e[:, 1], -e[:, 0]]) / np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-9)[:, None]
    shade = look.ambient + look.diffuse * np.abs(nrm @ light)
    sr, sc = np.nonzero(side)
    rgb[sr, sc] = clutter_colours(cl, obj[sc], h_in[sr, sc], top[sc], z_in[sc], sc) * shade[sc, None]
    px.depth[sr, sc] = z_in[sc]
    ids[sr, sc] = -1
    lr, lc = np.nonzero(lid & ~side)
    if len(lr):
        rgb[lr, lc] = cl.rgb[obj[lc]] * 1.1 * (look.ambient + look.diffuse)
        px.depth[lr, lc] = (cz - top[lc]) / rv[lr]
        ids[lr, lc] = -1
    px.void[side | lid] = False


def _fade(rgb: np.ndarray, px: _Pixels, look: Look, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Light falloff with depth and fog beyond range: the uint8 image and the depth (0: no return)."""
    depth = np.where(px.void | (px.depth > max_range), 0.0, px.depth)
    atten = 1.0 / (1.0 + look.falloff * np.where(depth > 0, depth, max_range))
    rgb *= atten[..., None]
    far = np.clip((depth - 0.6 * max_range) / (0.4 * max_range), 0.0, 1.0)
    far = np.where(depth > 0, far, 1.0)
    rgb = rgb * (1.0 - far[..., None]) + look.fog_rgb * far[..., None]
    return np.clip(rgb, 0, 255).astype(np.uint8), depth


def _feature_codes(scene: Scene) -> np.ndarray:
    """Look code of each feature: 0 door, 1 lift, 2 stairs (by class name; others look like doors)."""
    codes = {"door": 0, "lift": 1, "stairs": 2}
    return np.array([codes.get(f.class_name, 0) for f in scene.features], dtype=int)


def _visible_features(
    scene: Scene, ids: np.ndarray, cam: np.ndarray, fwd: np.ndarray, right: np.ndarray, camera: Camera
) -> list[VisibleFeature]:
    present = np.unique(ids)
    present = present[present >= 0]
    out = []
    panels = scene.feature_panels
    tangents = panels.tangent
    for k in present:
        mask = ids == k
        rows = np.flatnonzero(mask.any(axis=1))
        cols = np.flatnonzero(mask.any(axis=0))
        n = int(mask.sum())
        full, in_image, depth = _projected_rect(
            cam,
            fwd,
            right,
            panels.centre[k],
            tangents[k],
            float(panels.half_width[k]),
            float(panels.top[k]),
            camera,
        )
        f = scene.features[int(k)]
        out.append(
            VisibleFeature(
                index=int(k),
                feature_id=f.id,
                class_name=f.class_name,
                box=(float(cols[0]), float(rows[0]), float(cols[-1] + 1), float(rows[-1] + 1)),
                visible_fraction=min(1.0, n / full) if full > 0 else 0.0,
                in_image_fraction=min(1.0, in_image / full) if full > 0 else 0.0,
                pixels=n,
                distance=depth,
            )
        )
    return out
