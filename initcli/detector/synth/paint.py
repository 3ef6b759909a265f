"""The colours the raycaster (:mod:`initcli.detector.synth.render`) gives the pixels of features
(doors, lifts, stairs), wall decorations and clutter, from their :class:`Look` and where on the
object each pixel lies. Vectorised over pixels; pure functions."""

from __future__ import annotations

import numpy as np

from initcli.detector.synth.look import TEX, FeatureLooks, noise_tile
from initcli.detector.synth.scene import (
    CLUTTER_PERSON,
    DECOR_CABINET,
    DECOR_CALL_PANEL,
    DECOR_EXIT_SIGN,
    DECOR_INDICATOR,
    DECOR_POSTER,
    DECOR_SWITCH,
    DECOR_WINDOW,
    Clutter,
)

__all__ = ["clutter_colours", "decoration_colours", "feature_colours", "texture"]


def texture(rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """The noise tile (:func:`noise_tile`, about [-1, 1]) sampled at (rows, cols), wrapped."""
    tile = noise_tile()
    return tile[rows.astype(np.int64) % TEX, cols.astype(np.int64) % TEX]


def feature_colours(
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
        tex = texture(h * 6.0 + fid * 37, u * 160.0)
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
        tex = texture(h * 4.0 + fid * 53, u * 320.0)
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


def decoration_colours(
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
        tex = texture(h * 60 + did * 31, a * 60)
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


def clutter_colours(
    cl: Clutter, o: np.ndarray, hh: np.ndarray, top: np.ndarray, z_in: np.ndarray, sc: np.ndarray
) -> np.ndarray:
    """Colour of clutter side pixels (object ``o``, height ``hh``): banded boxes, people in vests."""
    base = cl.rgb[o] * (1.0 + 0.15 * texture(hh * 40.0 + o * 17, z_in * 3 + sc * 0.5))[:, None]
    person = cl.kind[o] == CLUTTER_PERSON
    rel = hh / np.maximum(top, 1e-3)
    vest = person & (rel > 0.5) & (rel < 0.82)
    head = person & (rel >= 0.86)
    legs = person & (rel <= 0.5)
    base = np.where(vest[:, None], np.array([250.0, 170.0, 30.0]), base)
    base = np.where(head[:, None], np.array([200.0, 150.0, 120.0]), base)
    base = np.where(legs[:, None], np.array([45.0, 50.0, 70.0]), base)
    bands = (~person) & ((np.floor(hh * 6.0 + o) % 4) == 0)
    return np.where(bands[:, None], base * 0.75, base)
