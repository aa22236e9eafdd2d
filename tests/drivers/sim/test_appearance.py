"""The renderer's appearances: speckle unchanged, the fitted realistic gel, real captures.

Truth comes from the captures themselves (a capture at rest renders as itself), the FOTS
authors' marker positions for them, known shifts (markers move by them, the LED shading
stays) and the project's estimator as the reader of warped captures.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from controller.tactile.estimator import TactileEstimator
from controller.tactile.settings import estimator_config
from core.sensor_profile import sensor_profile
from drivers.sim.render.appearance import appearance_names
from drivers.sim.render.field_grid import GridUpsampler
from drivers.sim.render.gel_analysis import find_markers, masked_blur
from drivers.sim.render.gel_pattern import blurred_disc_coverage, octave_texture
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.lighting import random_led_shading
from drivers.sim.render.marker_images import (
    MarkerImageRenderer,
    area_mean_field,
    smooth_random_field,
)
from drivers.sim.render.real_texture import (
    REAL_GELS_DIR,
    fit_to_size,
    load_capture,
    real_gel_names,
)
from drivers.sim.render.realistic import REALISTIC
from tests.drivers.sim.effects import ALL

HW = (240, 320)
REAL_MARKERS = "real:gelsight_markers_a"


def smooth_grid(grid_hw, amplitude_px, seed):
    full = smooth_random_field(HW, amplitude_px, np.random.default_rng(seed))
    return cv2.resize(full, grid_hw[::-1], interpolation=cv2.INTER_AREA)


def uniform(dx, dy, grid_hw=(48, 64)):
    return np.broadcast_to(np.float32([dx, dy]), (*grid_hw, 2))


def matched(found, expected):
    """Distance (px) from each expected centre to the nearest found one."""
    return cKDTree(found).query(expected)[0]


# -- names -----------------------------------------------------------------------------------


def test_speckle_is_the_default_and_the_same_by_name():
    field, start = smooth_grid((48, 64), 2.0, 1), smooth_grid((48, 64), 1.0, 2)
    for pitch in (31.5, None):
        default = GelRenderer(pitch_px=pitch, effects=ALL, rng=np.random.default_rng(4))
        named = GelRenderer(
            pitch_px=pitch, effects=ALL, rng=np.random.default_rng(4), appearance="speckle"
        )
        for renderer_args in ({}, {"frame_index": 2, "drift": 0.3, "exposure_start_px": start}):
            np.testing.assert_array_equal(
                default.render(field, **renderer_args), named.render(field, **renderer_args)
            )
    full = smooth_random_field(HW, 2.0, np.random.default_rng(1))
    exact = MarkerImageRenderer(rng=np.random.default_rng(4))
    exact_named = MarkerImageRenderer(rng=np.random.default_rng(4), appearance="speckle")
    np.testing.assert_array_equal(exact.render(full), exact_named.render(full))


def test_every_shipped_capture_is_an_appearance_and_unknown_names_are_refused():
    names = appearance_names()
    assert {"speckle", "realistic", "realistic_digit"} <= set(names)
    images = sorted(p.stem for p in REAL_GELS_DIR.iterdir() if p.suffix in (".png", ".jpg"))
    assert images == list(real_gel_names()) and len(images) == 5
    assert all(f"real:{name}" in names for name in images)
    for bad in ("glossy", "real:nope", "real:", 3):
        with pytest.raises(ValueError, match=r"appearance: expected one of speckle.*real:digit"):
            GelRenderer(appearance=bad)


# -- real captures ---------------------------------------------------------------------------


def test_fit_to_size_turns_portraits_and_crops_about_the_centre():
    portrait = np.zeros((320, 240, 3), np.uint8)
    portrait[0, 0] = 255  # top-left goes to the top-right when turned clockwise
    turned = fit_to_size(portrait, HW)
    assert turned.shape == (*HW, 3) and turned[0, -1, 0] == 255
    wide = np.arange(240 * 340).reshape(240, 340).astype(np.float32)
    np.testing.assert_array_equal(fit_to_size(wide, HW), wide[:, 10:330])
    tall = np.arange(250 * 320).reshape(250, 320).astype(np.float32)
    np.testing.assert_array_equal(fit_to_size(tall, HW), tall[5:245])
    large = np.random.default_rng(0).uniform(0, 255, (480, 640)).astype(np.float32)
    expected = cv2.resize(large, (320, 240), interpolation=cv2.INTER_AREA)
    np.testing.assert_allclose(fit_to_size(large, HW), expected)


@pytest.mark.parametrize("name", real_gel_names())
def test_a_capture_at_rest_renders_as_itself(name):
    expected = fit_to_size(load_capture(name), HW).astype(int)
    assert np.abs(GelRenderer(appearance=f"real:{name}").render() - expected).max() <= 1


@pytest.mark.parametrize("name", ["gelsight_markers_a", "gelsight_markers_b"])
def test_markers_found_in_the_captures_are_the_fots_authors_markers(name):
    rows = np.loadtxt(REAL_GELS_DIR / f"{name}.csv", delimiter=",", skiprows=1)
    positions = rows[:, :2] + rows[:, 2:]  # reference positions plus displacements, whole px
    found = GelRenderer(appearance=f"real:{name}").marker_centres_px
    distance = matched(found, positions)  # two roundings: up to 1 px per axis, and theirs
    assert abs(len(found) - len(positions)) <= 2
    assert np.mean(distance < 2.0) >= 0.9 and np.median(distance) < 1.0


def test_a_warped_capture_moves_its_markers_but_not_its_led_shading():
    shift = np.array([8.0, -6.0])
    for name in ("gelsight_markers_a", "gelsight_background"):
        renderer = GelRenderer(appearance=f"real:{name}")
        rest, moved = renderer.render(), renderer.render(uniform(*shift))

        def low(image):
            return masked_blur(image.astype(np.float32), ~find_markers(image).mask, 16.0)

        inner = (slice(30, -30), slice(30, -30))
        static = np.abs(low(moved) - low(rest))[inner].mean()
        warped_whole = np.roll(rest, (int(shift[1]), int(shift[0])), axis=(0, 1))
        if_whole = np.abs(low(warped_whole) - low(rest))[inner].mean()
        assert static < 1.0 and if_whole > 3 * static, (name, static, if_whole)
        if len(renderer.marker_centres_px):
            distance = matched(find_markers(moved).centres_px, renderer.marker_centres_px + shift)
            assert np.median(distance) < 0.05 and np.percentile(distance, 90) < 0.15


def test_the_estimator_reads_the_field_warped_into_a_capture():
    profile = sensor_profile("gelsight_mini")
    renderer = GelRenderer(effects=ImageEffects(noise_grey=2.0), appearance=REAL_MARKERS)
    field = smooth_grid((48, 64), 2.0, seed=21)
    estimator = TactileEstimator(estimator_config("paper"), profile)
    estimator.set_reference(renderer.render(frame_index=0))
    estimator.push(renderer.render(field, frame_index=1), 0.0)
    grid = estimator.field
    measured = np.stack([grid.u_mm, grid.v_mm], axis=2) / profile.mm_per_px
    truth = area_mean_field(GridUpsampler((48, 64), HW)(field), *measured.shape[:2])
    assert np.sqrt(((measured - truth) ** 2).sum(-1).mean()) < 0.06


# -- effects and the exact mode on every appearance -------------------------------------------


@pytest.mark.parametrize("appearance", ["realistic", "realistic_digit", REAL_MARKERS])
def test_marker_dropout_wears_off_the_chosen_markers(appearance):
    effects = ImageEffects(marker_dropout_fraction=0.3)
    worn = GelRenderer(effects=effects, rng=np.random.default_rng(6), appearance=appearance)
    kept, dropped = worn.marker_centres_px, worn.dropped_marker_centres_px
    assert len(dropped) == round(0.3 * (len(kept) + len(dropped))) > 5
    for image in (worn.render(), worn.render(uniform(0.4, -0.3))):
        found = find_markers(image).centres_px
        assert np.min(matched(found, dropped)) > 5.0
        assert np.mean(matched(found, kept) < 1.0) > 0.95


def test_every_effect_acts_on_a_colour_capture_and_occlusion_stays_put():
    renderer = GelRenderer(effects=ALL, rng=np.random.default_rng(9), appearance=REAL_MARKERS)
    field, start = smooth_grid((48, 64), 2.0, 5), smooth_grid((48, 64), 1.0, 6)
    image = renderer.render(field, frame_index=3, drift=0.5, exposure_start_px=start)
    assert image.dtype == np.uint8 and image.shape == (*HW, 3)
    still = GelRenderer(
        effects=dataclasses.replace(ALL, blur_sigma_px=0.0),
        rng=np.random.default_rng(9),
        appearance=REAL_MARKERS,
    )
    covered = still.occlusion_alpha > 0.9999
    assert covered.sum() > 100
    images = [still.render(f, frame_index=1) for f in (None, field)]
    np.testing.assert_array_equal(images[0][covered], images[1][covered])


@pytest.mark.parametrize("appearance", ["realistic", "real:digit_background_a"])
def test_the_exact_renderer_draws_the_same_gel(appearance):
    fast = GelRenderer(rng=np.random.default_rng(3), appearance=appearance)
    exact = MarkerImageRenderer(rng=np.random.default_rng(3), appearance=appearance)
    np.testing.assert_array_equal(fast.render(), exact.render())
    np.testing.assert_array_equal(fast.marker_centres_px, exact.marker_centres_px)
    field = smooth_random_field(HW, 2.0, np.random.default_rng(1))
    assert np.abs(fast.render(field).astype(int) - exact.render(field)).mean() < 0.5


# -- the realistic gel's parts ---------------------------------------------------------------


def test_realistic_markers_are_where_the_renderer_says_and_the_gel_is_seeded():
    renderer = GelRenderer(rng=np.random.default_rng(2), appearance="realistic")
    found = find_markers(renderer.render()).centres_px
    centres = renderer.marker_centres_px
    assert len(found) == len(centres)
    inside = np.all((centres > 12) & (centres < np.array(HW[::-1]) - 12), axis=1)
    assert inside.sum() > 40 and matched(found, centres[inside]).max() < 0.1
    again = GelRenderer(rng=np.random.default_rng(2), appearance="realistic").render()
    other = GelRenderer(rng=np.random.default_rng(3), appearance="realistic").render()
    np.testing.assert_array_equal(renderer.render(), again)
    assert np.abs(other.astype(int) - again).mean() > 5  # another lighting


def test_blurred_disc_edges_have_the_requested_radius_and_width():
    coverage = blurred_disc_coverage((81, 81), np.array([[40.0, 40.0]]), 40.0, 4.0)
    profile = coverage[40, 40:]  # r = 0, 1, ... px
    assert profile[0] == pytest.approx(1.0) and profile[20] == pytest.approx(0.5)
    r90, r10 = np.interp([0.9, 0.1], profile[::-1], np.arange(41)[::-1])
    assert r10 - r90 == pytest.approx(2.563 * 4.0, rel=0.01)
    assert not blurred_disc_coverage((8, 8), np.empty((0, 2)), 5.0, 1.0).any()


def test_octave_texture_has_the_requested_band_powers():
    rng = np.random.default_rng(0)
    texture = octave_texture(HW, (0.01, 0.0, 0.02, 0.0, 0.0), (0, 1, 2, 4, 8, 16), rng)
    assert abs(texture.mean()) < 1e-3
    assert texture.std() == pytest.approx(np.hypot(0.01, 0.02), rel=0.03)
    with pytest.raises(ValueError, match="band_sigmas_px"):
        octave_texture(HW, (0.01,), (0, 1, 2), rng)


def test_random_led_shading_has_the_requested_channel_statistics():
    shading = random_led_shading(
        HW, (150, 120, 100), (10, 15, 20), (-0.5, 0.2, 0.3), 100.0, np.random.default_rng(1)
    ).reshape(-1, 3)
    np.testing.assert_allclose(shading.mean(axis=0), (150, 120, 100), atol=1e-2)
    np.testing.assert_allclose(shading.std(axis=0), (10, 15, 20), rtol=1e-3)
    correlation = np.corrcoef(shading.T)
    np.testing.assert_allclose(correlation[[0, 0, 1], [1, 2, 2]], (-0.5, 0.2, 0.3), atol=1e-3)


def test_realistic_looks_are_validated_with_the_key_named():
    for key, value in [
        ("marker_ink", 1.5),
        ("texture_band_rms", (0.01, 0.01)),
        ("light_correlation_bg_br_gr", (0.9, 0.9, -0.9)),
    ]:
        with pytest.raises(ValueError, match=key):
            dataclasses.replace(REALISTIC, **{key: value})
