"""Appearance statistics (evaluation/appearance/stats.py) on images with known answers, and the
``realistic`` renders held within stated bounds of the real captures' statistics."""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest

from drivers.sim.render.gel_pattern import blurred_disc_coverage, marker_lattice
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.realistic import REALISTIC, RealisticLook
from evaluation.appearance.figure import mini_pitch_px, plot
from evaluation.appearance.fit import (
    capture_stats,
    fit_look,
    lattice_fit,
    look_source,
    rendered_stats,
)
from evaluation.appearance.stats import measure, summarise, table_rows

HW = (240, 320)


def disc_image(diameter_px, ink, edge_sigma_px, noise_grey=0.0, seed=0):
    """Grey discs on a 28 px lattice under a flat 200 grey level, as BGR uint8."""
    rng = np.random.default_rng(seed)
    centres = marker_lattice(HW, 28.0, 1.0, rng)
    coverage = blurred_disc_coverage(HW, centres, diameter_px, edge_sigma_px)
    grey = 200.0 * (1.0 - ink * coverage) + rng.normal(0.0, noise_grey, HW)
    return np.repeat(np.clip(np.rint(grey), 0, 255).astype(np.uint8)[..., None], 3, axis=2)


# -- known answers ---------------------------------------------------------------------------


@pytest.mark.parametrize(("diameter", "ink", "sigma"), [(11.0, 0.7, 0.6), (7.0, 0.5, 1.2)])
def test_marker_statistics_of_known_discs(diameter, ink, sigma):
    stats = measure(disc_image(diameter, ink, sigma))
    assert stats.marker_count == len(marker_lattice(HW, 28.0, 1.0, np.random.default_rng(0)))
    assert stats.marker_pitch_px == pytest.approx(28.0, abs=1.0)
    assert stats.marker_diameter_px == pytest.approx(diameter, abs=0.15)
    assert stats.marker_darkness == pytest.approx(ink, abs=0.02)
    assert stats.marker_edge_10_90_px == pytest.approx(2.563 * sigma, abs=0.15)


def test_noise_statistic_reads_white_noise_and_ignores_markers_and_gradients():
    for sigma in (1.0, 3.0):
        stats = measure(disc_image(11.0, 0.7, 0.6, noise_grey=sigma, seed=2))
        assert stats.noise_grey == pytest.approx(sigma, rel=0.1)
    xs = np.linspace(-40, 40, HW[1])[None, :] + np.linspace(-20, 20, HW[0])[:, None]
    ramp = np.repeat((128 + xs)[..., None], 3, axis=2)
    stats = measure(np.rint(ramp).astype(np.uint8))
    assert stats.noise_grey < 0.35  # rounding to uint8 only: 1/sqrt(12) = 0.29 at most
    assert max(stats.band_rms_grey) < 0.35  # a plane has no band-pass content
    inner = ramp[8:-8, 8:-8, 0]
    assert stats.low_rms_grey == pytest.approx(inner.std(), rel=0.05)
    assert stats.shading_spread_bgr[0] == pytest.approx(inner.std(), rel=0.05)


def test_octave_bands_pick_out_the_wavelength_of_a_pattern():
    ys, xs = np.mgrid[0 : HW[0], 0 : HW[1]]
    for wavelength, band in ((8.0, 1), (32.0, 3)):
        wave = 128 + 10 * np.sin(2 * np.pi * xs / wavelength)
        stats = measure(np.repeat(wave[..., None], 3, axis=2).astype(np.uint8))
        assert int(np.argmax(stats.band_rms_grey)) == band


def test_summarise_takes_medians_over_the_images_where_a_statistic_was_measured():
    with_markers, without = measure(disc_image(11.0, 0.7, 0.6)), measure(disc_image(11.0, 0, 1))
    merged = summarise([with_markers, without, with_markers])
    assert merged.marker_count == with_markers.marker_count
    assert merged.marker_diameter_px == with_markers.marker_diameter_px
    assert math.isnan(summarise([without]).marker_diameter_px)
    with pytest.raises(ValueError, match="stats"):
        summarise([])


def test_misshapen_images_are_refused():
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        measure(np.zeros((20, 20, 3), np.uint8))


# -- the fit's helpers -------------------------------------------------------------------------


def test_lattice_fit_recovers_pitch_and_jitter():
    rng = np.random.default_rng(3)
    for jitter in (0.0, 0.8, 2.0):
        positions = np.rint(marker_lattice((480, 640), 28.7, jitter, rng))
        pitch_x, pitch_y, found = lattice_fit(positions)
        assert pitch_x == pytest.approx(28.7, abs=0.05) and pitch_y == pytest.approx(28.7, abs=0.05)
        assert found == pytest.approx(jitter, abs=0.2)


def test_look_source_is_the_look_to_four_digits():
    source = look_source("copy", REALISTIC)
    namespace = {"RealisticLook": RealisticLook}
    exec(source, namespace)
    assert namespace["COPY"] == REALISTIC


# -- rendered against real -------------------------------------------------------------------

# Bounds on |rendered - real| (or the ratio rendered / real), and why:
# - marker diameter within 0.6 px (5 %), darkness within 0.05, 10-90 % edge within 0.3 px: the
#   fit matches them to 0.01 on its own seeds; the margin is for other seeds' lattices, and
#   a 1 px-sampled edge is not measurable much finer than 0.3 px.
# - channel means within 10 grey levels (5 %), shading spreads and the low part's RMS within
#   a factor 1.25, correlations within 0.15: the lighting is drawn per seed with exact
#   moments, so only the marker mask and clipping at 255 move them.
# - octave-band RMS in the 2-50 px bands and noise within a factor 1.6 (per seed they vary by
#   3 % or less); the 50-100 px band within a factor 1.8: the captures hold more power there
#   than at 25-50 px (the GelSight pair's pressed sphere, the DIGIT pair's LED lobes), which
#   a texture of white noise band-passed in octaves cannot reach without overshooting 25-50
#   px; the fit lands at 0.67-0.75 of it, varying by 4-6 % per seed. The speckle gel is 2.4-5.8x
#   the captures in the 2-50 px bands, so the bounds separate it clearly (checked below).
BOUNDS_ABS = {
    "marker diameter px": 0.6,
    "marker darkness": 0.05,
    "marker edge 10-90 % px": 0.3,
    **{f"mean {c}": 10.0 for c in "BGR"},
    **{f"shading correlation {p}": 0.15 for p in ("B-G", "B-R", "G-R")},
}
BOUNDS_RATIO = {
    **{f"shading spread {c}": 1.25 for c in "BGR"},
    "low part RMS": 1.25,
    **{f"band {b} RMS": 1.6 for b in ("2-6px", "6-12px", "12-25px", "25-50px")},
    "band 50-100px RMS": 1.8,
    "noise": 1.6,
}
SEEDS = (30, 31)  # not the fit's seeds


def out_of_bounds(rendered, real):
    got, want = table_rows(rendered), table_rows(real)
    failures = []
    for key, bound in BOUNDS_ABS.items():
        if np.isfinite(want[key]) and not abs(got[key] - want[key]) <= bound:
            failures.append((key, got[key], want[key]))
    for key, bound in BOUNDS_RATIO.items():
        if not 1 / bound <= got[key] / want[key] <= bound:
            failures.append((key, got[key], want[key]))
    return failures


@pytest.fixture(scope="module")
def captures():
    return {
        "realistic": capture_stats(("gelsight_markers_a", "gelsight_markers_b")),
        "realistic_digit": capture_stats(("digit_background_a", "digit_background_b")),
    }


@pytest.mark.parametrize(
    ("look", "pitch_px"), [("realistic", mini_pitch_px()), ("realistic_digit", None)]
)
def test_realistic_renders_are_within_bounds_of_the_captures(captures, look, pitch_px):
    for seed in SEEDS:
        image = GelRenderer(pitch_px=pitch_px, rng=np.random.default_rng(seed), appearance=look)
        assert out_of_bounds(measure(image.render()), captures[look]) == []


def test_the_speckle_gel_is_out_of_those_bounds(captures):
    image = GelRenderer(pitch_px=mini_pitch_px(), rng=np.random.default_rng(SEEDS[0])).render()
    failures = {key for key, _, _ in out_of_bounds(measure(image), captures["realistic"])}
    assert {"band 6-12px RMS", "band 12-25px RMS", "marker diameter px"} <= failures
    blurred = cv2.GaussianBlur(image, (0, 0), 3.0)  # blurring is no cure: edges go soft
    assert "marker edge 10-90 % px" in {
        k for k, _, _ in out_of_bounds(measure(blurred), captures["realistic"])
    }


# -- the figure and the fit --------------------------------------------------------------------


def test_the_figure_is_written(tmp_path):
    path = tmp_path / "appearance.png"
    plot(path)
    image = cv2.imread(str(path))
    assert image is not None and image.shape[0] > 600 and image.shape[1] > 800


@pytest.mark.slow
def test_the_fit_recovers_a_look_from_its_own_statistics():
    target = rendered_stats(REALISTIC, 28.0, seeds=(40, 41), noise_grey=1.0)
    start = dataclasses.replace(
        REALISTIC,
        marker_diameter_px=9.0,
        marker_ink=0.5,
        marker_edge_sigma_px=1.0,
        texture_band_rms=(0.01,) * 5,
        light_spread_bgr=(10.0, 10.0, 10.0),
    )
    look, noise_grey = fit_look(target, start, 28.0, rounds=3)
    assert look.marker_diameter_px == pytest.approx(REALISTIC.marker_diameter_px, abs=0.2)
    assert look.marker_ink == pytest.approx(REALISTIC.marker_ink, abs=0.02)
    assert look.marker_edge_sigma_px == pytest.approx(REALISTIC.marker_edge_sigma_px, abs=0.1)
    np.testing.assert_allclose(look.light_spread_bgr, REALISTIC.light_spread_bgr, rtol=0.1)
    assert noise_grey == pytest.approx(1.0, abs=0.25)
