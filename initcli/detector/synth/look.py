"""Appearance of a rendered scene: textures, colours of walls, floor, ceiling and each feature, light.

:func:`default_look` is fixed (the simulator's camera); :func:`random_look` is the domain
randomisation of the synthetic datasets (colours, textures, door styles, lighting).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

__all__ = [
    "DOORS",
    "FLOORS",
    "FeatureLooks",
    "LIFTS",
    "Look",
    "STAIRS",
    "TEX",
    "WALLS",
    "default_feature_looks",
    "default_look",
    "noise_tile",
    "random_feature_looks",
    "random_look",
]

TEX = 256  # texture tile size (pixels)


@lru_cache(maxsize=1)
def noise_tile() -> np.ndarray:
    """A fixed, tileable, multi-octave value-noise tile in about [-1, 1] (float32, TEX x TEX)."""
    rng = np.random.default_rng(12345)
    out = np.zeros((TEX, TEX), dtype=np.float32)
    amp = 1.0
    for cells in (4, 16, 64, 256):
        coarse = rng.standard_normal((cells, cells)).astype(np.float32)
        rep = TEX // cells
        # bilinear upsampling with wrap-around keeps the tile seamless
        idx = (np.arange(TEX) / rep).astype(np.float32)
        i0 = np.floor(idx).astype(int) % cells
        i1 = (i0 + 1) % cells
        w = (idx - np.floor(idx))[:, None]
        rows = coarse[i0] * (1 - w) + coarse[i1] * w
        up = rows[:, i0] * (1 - w.T) + rows[:, i1] * w.T
        out += amp * up
        amp *= 0.6
    out /= np.abs(out).max()
    return out


@dataclass
class FeatureLooks:
    """Per-feature appearance arrays (length F, indexed like ``Scene.features``)."""

    leaf_rgb: np.ndarray  # (F, 3) door leaf / lift panels / stair treads
    frame_rgb: np.ndarray  # (F, 3) frame, lift surround, stair reveal
    accent_rgb: np.ndarray  # (F, 3) handle, lift seam, stair risers
    frame_w: np.ndarray  # (F,) m
    grain: np.ndarray  # (F,) texture amplitude
    handle_side: np.ndarray  # (F,) -1 left, +1 right
    vision: np.ndarray  # (F,) bool: glazed vision panel (doors), mirror band (lifts)
    kick: np.ndarray  # (F,) bool: kick plate (doors)
    double: np.ndarray  # (F,) bool: two leaves (doors), side-opening (lifts)
    plate: np.ndarray  # (F,) bool: number plate (doors)
    steps: np.ndarray  # (F,) visible stair steps
    step_gamma: np.ndarray  # (F,) perspective of the flight
    rail_side: np.ndarray  # (F,) -1 / +1
    interior_rgb: np.ndarray  # (F, 3) stairwell walls


@dataclass
class Look:
    """Global appearance of one image plus the per-feature arrays."""

    wall_rgb: np.ndarray = field(default_factory=lambda: np.array([214.0, 210.0, 200.0]))
    wall_tex: float = 0.04
    wall_tex_scale: float = 40.0  # texture pixels per metre
    skirting_h: float = 0.1
    skirting_rgb: np.ndarray = field(default_factory=lambda: np.array([90.0, 90.0, 95.0]))
    floor_rgb: np.ndarray = field(default_factory=lambda: np.array([150.0, 148.0, 140.0]))
    floor_rgb2: np.ndarray = field(default_factory=lambda: np.array([140.0, 138.0, 130.0]))
    floor_tile: float = 0.6
    grout: float = 0.03  # fraction of a tile
    grout_rgb: np.ndarray = field(default_factory=lambda: np.array([110.0, 108.0, 104.0]))
    floor_tex: float = 0.06
    ceiling_rgb: np.ndarray = field(default_factory=lambda: np.array([225.0, 225.0, 222.0]))
    ceiling_grid: float = 0.6  # m, 0 = plain
    lights: float = 2.4  # m between ceiling lights, 0 = none
    ambient: float = 0.65
    diffuse: float = 0.35
    light_angle: float = 0.6  # rad, direction of the dominant light in the plan
    falloff: float = 0.02  # brightness 1 / (1 + falloff * depth)
    fog_rgb: np.ndarray = field(default_factory=lambda: np.array([40.0, 40.0, 45.0]))
    features: FeatureLooks | None = None


def default_feature_looks(class_index: np.ndarray, class_names: tuple[str, ...]) -> FeatureLooks:
    """A plausible fixed look: wooden doors with lever handles, steel lifts, concrete stairs."""
    n = len(class_index)
    names = np.array([class_names[i] if 0 <= i < len(class_names) else "" for i in class_index])
    leaf = np.tile([150.0, 105.0, 65.0], (n, 1))
    frame = np.tile([120.0, 110.0, 100.0], (n, 1))
    accent = np.tile([60.0, 60.0, 62.0], (n, 1))
    fw = np.full(n, 0.06)
    lift, stairs = names == "lift", names == "stairs"
    leaf[lift] = [175.0, 178.0, 182.0]
    frame[lift] = [140.0, 142.0, 146.0]
    accent[lift] = [35.0, 35.0, 38.0]
    fw[lift] = 0.1
    leaf[stairs] = [175.0, 170.0, 160.0]
    frame[stairs] = [170.0, 168.0, 160.0]
    accent[stairs] = [110.0, 106.0, 100.0]
    fw[stairs] = 0.08
    return FeatureLooks(
        leaf_rgb=leaf,
        frame_rgb=frame,
        accent_rgb=accent,
        frame_w=fw,
        grain=np.full(n, 0.08),
        handle_side=np.ones(n),
        vision=np.zeros(n, bool),
        kick=np.zeros(n, bool),
        double=np.zeros(n, bool),
        plate=np.ones(n, bool),
        steps=np.full(n, 9.0),
        step_gamma=np.full(n, 0.8),
        rail_side=np.ones(n),
        interior_rgb=np.tile([120.0, 118.0, 112.0], (n, 1)),
    )


def default_look(class_index: np.ndarray, class_names: tuple[str, ...]) -> Look:
    return Look(features=default_feature_looks(class_index, class_names))


def _hsv_colour(
    rng: np.random.Generator, n: int, h: tuple[float, float], s: tuple[float, float], v: tuple[float, float]
) -> np.ndarray:
    """n random colours (0-255 floats) from HSV ranges (h in [0, 1))."""
    hh = rng.uniform(*h, n) % 1.0
    ss = rng.uniform(*s, n)
    vv = rng.uniform(*v, n) * 255.0
    i = np.floor(hh * 6).astype(int) % 6
    f = hh * 6 - np.floor(hh * 6)
    p, q, t = vv * (1 - ss), vv * (1 - f * ss), vv * (1 - (1 - f) * ss)
    table = np.stack(
        [np.stack(c, -1) for c in ((vv, t, p), (q, vv, p), (p, vv, t), (p, q, vv), (t, p, vv), (vv, p, q))]
    )
    return table[i, np.arange(n)]


def _pick(rng: np.random.Generator, options: list[tuple[tuple, tuple, tuple]], n: int) -> np.ndarray:
    """n colours, each from a palette entry chosen at random: (h range, s range, v range)."""
    which = rng.integers(len(options), size=n)
    out = np.zeros((n, 3))
    for k, (h, s, v) in enumerate(options):
        m = which == k
        if m.any():
            out[m] = _hsv_colour(rng, int(m.sum()), h, s, v)
    return out


WALLS = [
    ((0.0, 1.0), (0.0, 0.08), (0.7, 0.95)),  # off-white paint
    ((0.05, 0.15), (0.05, 0.3), (0.55, 0.9)),  # beige / sand
    ((0.0, 1.0), (0.0, 0.05), (0.45, 0.7)),  # grey concrete / plaster
    ((0.0, 1.0), (0.15, 0.45), (0.5, 0.9)),
]  # painted colour
FLOORS = [
    ((0.0, 1.0), (0.0, 0.08), (0.3, 0.75)),
    ((0.05, 0.12), (0.2, 0.5), (0.3, 0.7)),
    ((0.0, 1.0), (0.1, 0.4), (0.25, 0.6)),
]
DOORS = [
    ((0.04, 0.1), (0.35, 0.75), (0.3, 0.75)),  # wood
    ((0.0, 1.0), (0.0, 0.1), (0.2, 0.95)),  # painted white / grey / dark
    ((0.0, 1.0), (0.3, 0.85), (0.25, 0.8)),
]  # painted colour
LIFTS = [
    ((0.0, 1.0), (0.0, 0.06), (0.5, 0.9)),  # stainless
    ((0.5, 0.7), (0.03, 0.15), (0.45, 0.8)),  # blue-ish steel
    ((0.0, 1.0), (0.0, 0.1), (0.25, 0.5)),  # dark anodised
    ((0.05, 0.14), (0.2, 0.5), (0.5, 0.85)),
]  # gold / brass / wood laminate
STAIRS = [
    ((0.0, 1.0), (0.0, 0.08), (0.45, 0.85)),
    ((0.04, 0.12), (0.2, 0.6), (0.35, 0.75)),
    ((0.0, 1.0), (0.1, 0.5), (0.35, 0.8)),
]


def random_feature_looks(
    rng: np.random.Generator, class_index: np.ndarray, class_names: tuple[str, ...]
) -> FeatureLooks:
    """Per-feature random styles; features of a class share a style with probability 0.6."""
    n = len(class_index)
    names = np.array([class_names[i] if 0 <= i < len(class_names) else "" for i in class_index])
    looks = default_feature_looks(class_index, class_names)
    for cls, palette, frame_pal, accent_pal in (
        ("door", DOORS, WALLS + DOORS, [((0.0, 1.0), (0.0, 0.1), (0.1, 0.85))]),
        (
            "lift",
            LIFTS,
            LIFTS + [((0.0, 1.0), (0.0, 0.1), (0.1, 0.3))],
            [((0.0, 1.0), (0.0, 0.1), (0.02, 0.2))],
        ),
        ("stairs", STAIRS, WALLS, [((0.0, 1.0), (0.0, 0.3), (0.2, 0.6))]),
    ):
        m = names == cls
        k = int(m.sum())
        if not k:
            continue
        shared = rng.random() < 0.6
        count = 1 if shared else k
        for attr, pal in (("leaf_rgb", palette), ("frame_rgb", frame_pal), ("accent_rgb", accent_pal)):
            colours = _pick(rng, pal, count)
            getattr(looks, attr)[m] = colours if not shared else np.repeat(colours, k, axis=0)
    lift, stairs = names == "lift", names == "stairs"
    looks.frame_w[:] = rng.uniform(0.03, 0.12, n)
    looks.frame_w[lift] = rng.uniform(0.06, 0.18, int(lift.sum()))
    looks.frame_w[stairs] = rng.uniform(0.03, 0.15, int(stairs.sum()))
    looks.grain[:] = rng.uniform(0.0, 0.25, n)
    looks.handle_side[:] = rng.choice([-1.0, 1.0], n)
    looks.vision[:] = rng.random(n) < 0.3
    looks.kick[:] = rng.random(n) < 0.3
    looks.double[:] = rng.random(n) < 0.2
    looks.plate[:] = rng.random(n) < 0.5
    looks.steps[:] = rng.integers(5, 14, n)
    looks.step_gamma[:] = rng.uniform(0.6, 1.0, n)
    looks.rail_side[:] = rng.choice([-1.0, 1.0], n)
    looks.interior_rgb[:] = _pick(rng, WALLS, n) * rng.uniform(0.45, 0.9, (n, 1))
    return looks


def random_look(rng: np.random.Generator, class_index: np.ndarray, class_names: tuple[str, ...]) -> Look:
    """Domain randomisation of everything but geometry."""
    wall = _pick(rng, WALLS, 1)[0]
    floor = _pick(rng, FLOORS, 1)[0]
    return Look(
        wall_rgb=wall,
        wall_tex=float(rng.uniform(0.0, 0.15)),
        wall_tex_scale=float(rng.uniform(15.0, 120.0)),
        skirting_h=float(rng.choice([0.0, rng.uniform(0.05, 0.15)])),
        skirting_rgb=_pick(rng, FLOORS + WALLS, 1)[0],
        floor_rgb=floor,
        floor_rgb2=floor * rng.uniform(0.85, 1.1),
        floor_tile=float(rng.uniform(0.3, 1.2)),
        grout=float(rng.choice([0.0, rng.uniform(0.01, 0.06)])),
        grout_rgb=floor * rng.uniform(0.6, 1.2),
        floor_tex=float(rng.uniform(0.0, 0.2)),
        ceiling_rgb=_pick(rng, WALLS[:3], 1)[0],
        ceiling_grid=float(rng.choice([0.0, 0.6, 1.2])),
        lights=float(rng.choice([0.0, rng.uniform(1.5, 4.0)])),
        ambient=float(rng.uniform(0.4, 0.8)),
        diffuse=float(rng.uniform(0.1, 0.5)),
        light_angle=float(rng.uniform(0.0, np.pi)),
        falloff=float(rng.uniform(0.0, 0.08)),
        fog_rgb=_pick(rng, WALLS, 1)[0] * rng.uniform(0.1, 0.5),
        features=random_feature_looks(rng, class_index, class_names),
    )
