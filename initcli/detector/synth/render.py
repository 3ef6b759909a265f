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

from initcli.core.raycast import ray_segment_params
from initcli.detector.synth.look import TEX, FeatureLooks, Look, default_look, noise_tile
from initcli.detector.synth.scene import (
    CLUTTER_PERSON,
    DECOR_CABINET,
    DECOR_CALL_PANEL,
    DECOR_EXIT_SIGN,
    DECOR_INDICATOR,
    DECOR_POSTER,
    DECOR_SWITCH,
    DECOR_WINDOW,
    Camera,
    Panels,
    Scene,
)

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


def _tex(rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    tile = noise_tile()
    return tile[rows.astype(np.int64) % TEX, cols.astype(np.int64) % TEX]


def cast_rays(
    origin: np.ndarray, dirs: np.ndarray, segs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays ``origin + t * dirs`` (W, 2) against segments (S, 4): all t (W, S) (inf = miss), the
    position s along each segment and the hits (:func:`initcli.core.raycast.ray_segment_params`;
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


def _feature_colours(
    code: np.ndarray,
    a: np.ndarray,
    h: np.ndarray,
    hw: np.ndarray,
    top: np.ndarray,
    fl: FeatureLooks,
    fid: np.ndarray,
) -> np.ndarray:
    """Colour of feature pixels: code 0 door, 1 lift, 2 stairs; a across (m), h height (m)."""
    w = 2.0 * hw
    u = a + hw
    fw = fl.frame_w[fid]
    leaf = fl.leaf_rgb[fid]
    accent = fl.accent_rgb[fid]
    out = leaf.copy()
    grain = fl.grain[fid]
    mid = np.abs(u - hw)

    door = code == 0
    if door.any():
        tex = _tex(h * 6.0 + fid * 37, u * 160.0)
        out[door] *= (1.0 + grain * tex)[door, None]
        side = fl.handle_side[fid]
        hu = np.where(side > 0, w - fw - 0.1, fw + 0.1)
        rose = (np.abs(u - hu) < 0.03) & (np.abs(h - 1.0) < 0.06)
        lever = (np.abs(u - hu + side * 0.06) < 0.065) & (np.abs(h - 1.03) < 0.016)
        seam = fl.double[fid] & (mid < 0.008)
        vision = fl.vision[fid] & (mid < 0.09) & (h > 1.2) & (h < 1.8)
        kick = fl.kick[fid] & (h < 0.25)
        plate = fl.plate[fid] & (mid < 0.07) & (np.abs(h - 1.6) < 0.035)
        glass = np.array([55.0, 70.0, 80.0]) * (1.0 + 0.4 * (h - 1.2))[:, None]
        out = np.where((door & kick)[:, None], leaf * 0.3 + 120.0, out)
        out = np.where((door & vision)[:, None], glass, out)
        out = np.where((door & plate)[:, None], 255.0 - accent * 0.6, out)
        out = np.where((door & (rose | lever | seam))[:, None], accent, out)

    lift = code == 1
    if lift.any():
        tex = _tex(h * 4.0 + fid * 53, u * 320.0)
        band = 0.85 + 0.3 * (0.5 + 0.5 * np.sin(u * 2.3 + fid * 1.7))
        lit = leaf * ((1.0 + 0.6 * grain * tex) * band)[:, None]
        out = np.where(lift[:, None], lit, out)
        seam_u = np.where(fl.double[fid], fw + (w - 2 * fw) / 3.0, hw)
        seam = (np.abs(u - seam_u) < 0.007) | (np.abs(u - fw) < 0.006) | (np.abs(u - (w - fw)) < 0.006)
        sill = h < 0.04
        stripe = fl.vision[fid] & (np.abs(h - 1.0) < 0.025)
        out = np.where((lift & sill)[:, None], np.array([150.0, 150.0, 150.0]), out)
        out = np.where((lift & (seam | stripe))[:, None], accent, out)

    stairs = code == 2
    if stairs.any():
        inner = np.maximum(top - fw, 0.3)
        y = np.clip(h / inner, 0.0, 1.0)
        half_in = np.maximum(hw - fw, 0.05) * (1.0 - 0.35 * y)
        gamma = fl.step_gamma[fid]
        y_top = 0.45 + 0.4 * gamma
        s = (np.clip(y / y_top, 0, 1) ** gamma) * fl.steps[fid]
        frac = s - np.floor(s)
        tread = frac < 0.45
        nosing = np.abs(frac - 0.45) < 0.06
        shade_up = (1.0 - 0.35 * y)[:, None]
        step_col = np.where(tread[:, None], leaf, accent) * shade_up
        step_col = np.where(nosing[:, None], step_col * 0.55, step_col)
        interior = fl.interior_rgb[fid] * (0.65 + 0.35 * (1 - y))[:, None]
        col = np.where(((y >= y_top) | (mid > half_in))[:, None], interior, step_col)
        sgn = fl.rail_side[fid]
        x0 = hw + sgn * (hw - fw) * 0.95
        x1 = hw + sgn * (hw - fw) * 0.55
        t = np.clip((y - 0.45) / 0.5, 0.0, 1.0)
        rail = (np.abs(u - (x0 + (x1 - x0) * t)) < 0.025) & (y > 0.45) & (y < 0.95)
        col = np.where(rail[:, None], accent * 0.5, col)
        out = np.where(stairs[:, None], col, out)

    frame = (u < fw) | (u > w - fw) | (h > top - fw * np.where(code == 1, 1.6, 1.0))
    out = np.where(frame[:, None], fl.frame_rgb[fid], out)
    return out


def _decoration_colours(
    kind: np.ndarray,
    a: np.ndarray,
    h: np.ndarray,
    bottom: np.ndarray,
    top: np.ndarray,
    hw: np.ndarray,
    rgb: np.ndarray,
    did: np.ndarray,
) -> np.ndarray:
    out = rgb.copy()
    y = (h - bottom) / np.maximum(top - bottom, 1e-3)  # 0 at the bottom
    x = (a + hw) / np.maximum(2 * hw, 1e-3)  # 0 at the left
    border = (x < 0.06) | (x > 0.94) | (y < 0.06) | (y > 0.94)
    poster = kind == DECOR_POSTER
    if poster.any():
        tex = _tex(h * 60 + did * 31, a * 60)
        stripes = (np.floor(y * 7 + did) % 3 == 0) & (x > 0.15) & (x < 0.85)
        col = rgb * (1.0 + 0.35 * tex)[:, None]
        col = np.where(stripes[:, None], 255.0 - rgb * 0.7, col)
        out = np.where(poster[:, None], np.where(border[:, None], 235.0, col), out)
    panel = kind == DECOR_CALL_PANEL
    if panel.any():
        button = (np.abs(x - 0.5) < 0.25) & ((np.abs(y - 0.4) < 0.08) | (np.abs(y - 0.6) < 0.08))
        out = np.where((panel & button)[:, None], np.array([250.0, 190.0, 90.0]), out)
    indicator = kind == DECOR_INDICATOR
    if indicator.any():
        digits = (np.abs(x - 0.5) < 0.15) & (np.abs(y - 0.5) < 0.3) & (np.floor(x * 20) % 2 == 0)
        out = np.where((indicator & digits)[:, None], np.array([255.0, 120.0, 40.0]), out)
    exit_sign = kind == DECOR_EXIT_SIGN
    if exit_sign.any():
        figure = (np.abs(x - 0.3) < 0.12) & (np.abs(y - 0.5) < 0.3)
        arrow = (np.abs(x - 0.7) < 0.15) & (np.abs(y - 0.5) < 0.08)
        out = np.where((exit_sign & (figure | arrow))[:, None], 245.0, out)
    cabinet = kind == DECOR_CABINET
    if cabinet.any():
        glass = (np.abs(x - 0.5) < 0.3) & (np.abs(y - 0.55) < 0.25)
        out = np.where((cabinet & border)[:, None], 230.0, out)
        out = np.where((cabinet & glass)[:, None], rgb * 0.6, out)
    window = kind == DECOR_WINDOW
    if window.any():
        glass = np.array([120.0, 150.0, 170.0]) * (0.7 + 0.5 * y)[:, None]
        mullion = border | (np.abs(x - 0.5) < 0.02)
        out = np.where(window[:, None], np.where(mullion[:, None], rgb, glass), out)
    switch = kind == DECOR_SWITCH
    if switch.any():
        out = np.where((switch & (np.abs(y - 0.5) < 0.2) & (np.abs(x - 0.5) < 0.2))[:, None], rgb * 0.8, out)
    return out


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
    W, H = camera.width, camera.height
    cam = np.array([x0, y0])
    fwd = np.array([math.cos(yaw), math.sin(yaw)])
    right = np.array([fwd[1], -fwd[0]])
    xn = (np.arange(W) + 0.5 - camera.cx) / camera.fx
    dirs = fwd[None, :] + xn[:, None] * right[None, :]  # forward component 1: t is the optical depth
    rv = ((np.arange(H) + 0.5 - camera.cy) / camera.fy).astype(np.float64)
    cz, ceiling, max_range = camera.z, scene.ceiling, camera.max_range
    cols = np.arange(W)

    # --- walls: one ray per column ---------------------------------------------------------
    wall_ids = _visible_walls(scene, cam, fwd, max_range)
    if len(wall_ids):
        segs = scene.walls[wall_ids]
        t_all, s_all, _ = cast_rays(cam, dirs, segs)
        j = np.argmin(t_all, axis=1)
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
        z_wall = np.full(W, np.inf)
        hit_normal = -dirs / np.hypot(dirs[:, 0], dirs[:, 1])[:, None]
        tex_u = np.zeros(W)
    void_col = ~np.isfinite(z_wall) | (z_wall > max_range)
    z_wall = np.where(void_col, max_range, z_wall)
    hit = cam + dirs * z_wall[:, None]

    feat_col, feat_a = _panel_lookup(scene.feature_panels, cam, hit, dirs, hit_normal, max_range)
    feat_col[void_col] = -1
    dec_col, dec_a = _panel_lookup(scene.decorations, cam, hit, dirs, hit_normal, max_range)
    dec_col[void_col] = -1

    light = np.array([math.cos(look.light_angle), math.sin(look.light_angle)])
    shade_col = look.ambient + look.diffuse * np.abs(hit_normal @ light)

    # --- per pixel ----------------------------------------------------------------------------
    h_wall = cz - rv[:, None] * z_wall[None, :]  # height at which each pixel's ray meets the wall
    is_floor = h_wall < 0
    is_ceil = h_wall > ceiling
    is_wall = ~(is_floor | is_ceil)
    with np.errstate(divide="ignore"):
        z_floor = np.where(rv > 0, cz / np.where(rv > 0, rv, 1.0), np.inf)
        z_ceil = np.where(rv < 0, (ceiling - cz) / np.where(rv < 0, -rv, 1.0), np.inf)
    depth = np.where(is_wall, z_wall[None, :], np.where(is_floor, z_floor[:, None], z_ceil[:, None]))
    void = is_wall & void_col[None, :]

    rgb = np.empty((H, W, 3), dtype=np.float64)

    # walls
    wr, wc = np.nonzero(is_wall)
    hw_ = h_wall[wr, wc]
    tex = _tex(hw_ * look.wall_tex_scale, tex_u[wc] * look.wall_tex_scale)
    wall_col = look.wall_rgb[None, :] * (1.0 + look.wall_tex * tex)[:, None]
    if look.skirting_h > 0:
        wall_col = np.where((hw_ < look.skirting_h)[:, None], look.skirting_rgb, wall_col)
    wall_col *= (1.0 + 0.12 * (hw_ / ceiling - 0.5))[:, None]

    ids = np.full((H, W), -1, dtype=np.int16)
    fidx = feat_col[wc]
    on_feat = fidx >= 0
    if on_feat.any():
        fi = fidx[on_feat]
        hh = hw_[on_feat]
        inside = hh <= scene.feature_panels.top[fi]
        sel = np.flatnonzero(on_feat)[inside]
        fi = fi[inside]
        if len(sel):
            code = _feature_codes(scene)[fi]
            wall_col[sel] = _feature_colours(
                code,
                feat_a[wc[sel]],
                hw_[sel],
                scene.feature_panels.half_width[fi],
                scene.feature_panels.top[fi],
                fl,
                fi,
            )
            ids[wr[sel], wc[sel]] = fi
    didx = dec_col[wc]
    on_dec = (didx >= 0) & (ids[wr, wc] < 0)
    if on_dec.any():
        di = didx[on_dec]
        hh = hw_[on_dec]
        d = scene.decorations
        inside = (hh >= d.bottom[di]) & (hh <= d.top[di])
        sel = np.flatnonzero(on_dec)[inside]
        di = di[inside]
        if len(sel):
            wall_col[sel] = _decoration_colours(
                d.kind[di], dec_a[wc[sel]], hw_[sel], d.bottom[di], d.top[di], d.half_width[di], d.rgb[di], di
            )
    rgb[wr, wc] = wall_col * shade_col[wc, None]

    # floor
    fr, fc = np.nonzero(is_floor)
    zf = z_floor[fr]
    px = cam[0] + zf * dirs[fc, 0]
    py = cam[1] + zf * dirs[fc, 1]
    tile = look.floor_tile
    gx, gy = px / tile, py / tile
    checker = ((np.floor(gx) + np.floor(gy)) % 2 == 0)[:, None]
    floor_col = np.where(checker, look.floor_rgb, look.floor_rgb2)
    floor_col = floor_col * (1.0 + look.floor_tex * _tex(px * 50.0, py * 50.0))[:, None]
    if look.grout > 0:
        grout = ((gx - np.floor(gx)) < look.grout) | ((gy - np.floor(gy)) < look.grout)
        floor_col = np.where(grout[:, None], look.grout_rgb, floor_col)
    rgb[fr, fc] = floor_col * (look.ambient + 0.5 * look.diffuse)

    # ceiling
    cr, cc = np.nonzero(is_ceil)
    zc = z_ceil[cr]
    qx = cam[0] + zc * dirs[cc, 0]
    qy = cam[1] + zc * dirs[cc, 1]
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

    # clutter (free-standing boxes and people): side faces and visible top faces
    cl = scene.clutter
    if cl.count:
        near = np.flatnonzero(_segment_distance(cam, cl.segments) < max_range)
        if len(near):
            t_all, _, _ = cast_rays(cam, dirs, cl.segments[near])
            j = np.argmin(t_all, axis=1)
            z_in = t_all[cols, j]
            has = np.isfinite(z_in) & (z_in < z_wall)
            if has.any():
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
                nrm = (
                    np.column_stack([e[:, 1], -e[:, 0]])
                    / np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-9)[:, None]
                )
                shade = look.ambient + look.diffuse * np.abs(nrm @ light)
                sr, sc = np.nonzero(side)
                hh = h_in[sr, sc]
                o = obj[sc]
                base = cl.rgb[o] * (1.0 + 0.15 * _tex(hh * 40.0 + o * 17, z_in[sc] * 3 + sc * 0.5))[:, None]
                person = cl.kind[o] == CLUTTER_PERSON
                rel = hh / np.maximum(top[sc], 1e-3)
                vest = person & (rel > 0.5) & (rel < 0.82)
                head = person & (rel >= 0.86)
                legs = person & (rel <= 0.5)
                base = np.where(vest[:, None], np.array([250.0, 170.0, 30.0]), base)
                base = np.where(head[:, None], np.array([200.0, 150.0, 120.0]), base)
                base = np.where(legs[:, None], np.array([45.0, 50.0, 70.0]), base)
                bands = (~person) & ((np.floor(hh * 6.0 + o) % 4) == 0)
                base = np.where(bands[:, None], base * 0.75, base)
                rgb[sr, sc] = base * shade[sc, None]
                depth[sr, sc] = z_in[sc]
                ids[sr, sc] = -1
                lr, lc = np.nonzero(lid & ~side)
                if len(lr):
                    rgb[lr, lc] = cl.rgb[obj[lc]] * 1.1 * (look.ambient + look.diffuse)
                    depth[lr, lc] = (cz - top[lc]) / rv[lr]
                    ids[lr, lc] = -1
                void[side | lid] = False

    # light falloff, fog beyond range
    depth = np.where(void | (depth > max_range), 0.0, depth)
    atten = 1.0 / (1.0 + look.falloff * np.where(depth > 0, depth, max_range))
    rgb *= atten[..., None]
    far = np.clip((depth - 0.6 * max_range) / (0.4 * max_range), 0.0, 1.0)
    far = np.where(depth > 0, far, 1.0)
    rgb = rgb * (1.0 - far[..., None]) + look.fog_rgb * far[..., None]
    image = np.clip(rgb, 0, 255).astype(np.uint8)
    return View(
        image,
        depth.astype(np.float32),
        ids,
        _visible_features(scene, ids, cam, fwd, right, camera),
        camera,
        (x0, y0, yaw),
    )


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
