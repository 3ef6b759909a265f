"""initcli.detector.synth.look: the fixed look, the noise tile and the randomised looks."""

from __future__ import annotations

import numpy as np

from initcli.detector.synth.look import TEX, default_feature_looks, default_look, noise_tile, random_look

NAMES = ("door", "lift", "stairs")


def test_noise_tile_is_fixed_normalised_and_seamless() -> None:
    tile = noise_tile()
    assert tile.shape == (TEX, TEX) and tile.dtype == np.float32
    assert np.abs(tile).max() == np.float32(1.0)
    assert noise_tile() is tile  # cached
    # tileable: the step across the wrap is no larger than steps inside the tile
    inner = np.abs(np.diff(tile, axis=0)).max()
    assert np.abs(tile[0] - tile[-1]).max() <= inner + 1e-6
    inner = np.abs(np.diff(tile, axis=1)).max()
    assert np.abs(tile[:, 0] - tile[:, -1]).max() <= inner + 1e-6


def test_default_feature_looks_per_class() -> None:
    looks = default_feature_looks(np.array([0, 1, 2, 0, 7]), NAMES)
    assert looks.leaf_rgb.shape == (5, 3)
    np.testing.assert_array_equal(looks.leaf_rgb[0], looks.leaf_rgb[3])  # two doors alike
    assert not np.array_equal(looks.leaf_rgb[0], looks.leaf_rgb[1])  # a lift is steel, not wood
    assert looks.frame_w.tolist() == [0.06, 0.1, 0.08, 0.06, 0.06]  # unknown class 7: door defaults
    assert default_look(np.array([1]), NAMES).features is not None


def test_random_look_is_reproducible_and_in_range() -> None:
    classes = np.array([0, 0, 1, 2, 2, 2])
    a = random_look(np.random.default_rng(5), classes, NAMES)
    b = random_look(np.random.default_rng(5), classes, NAMES)
    c = random_look(np.random.default_rng(6), classes, NAMES)
    np.testing.assert_array_equal(a.wall_rgb, b.wall_rgb)
    np.testing.assert_array_equal(a.features.leaf_rgb, b.features.leaf_rgb)
    assert not np.array_equal(a.wall_rgb, c.wall_rgb)
    for look in (a, c):
        for rgb in (look.wall_rgb, look.floor_rgb, look.ceiling_rgb, look.features.leaf_rgb):
            assert (rgb >= 0).all() and (rgb <= 255.0 + 1e-9).all()
        assert 0.4 <= look.ambient <= 0.8
        f = look.features
        assert set(np.unique(f.handle_side)) <= {-1.0, 1.0}
        assert ((f.steps >= 5) & (f.steps < 14)).all()
        assert (f.frame_w[classes == 1] >= 0.06).all()


def test_random_looks_vary_over_many_seeds() -> None:
    classes = np.array([0, 0, 0, 0])
    shared = 0
    for seed in range(40):
        leaf = random_look(np.random.default_rng(seed), classes, NAMES).features.leaf_rgb
        shared += int(np.allclose(leaf, leaf[0]))
    assert 10 < shared < 40  # doors share one style with probability 0.6
