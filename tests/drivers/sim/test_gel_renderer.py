"""The fast gel renderer: field convention at any resolution, seeded effects, flow truth.

Truth comes from analytic fields (affine fields have affine inverses), the exact full-
resolution inversion and spline renderer (drivers/sim/render/marker_images.py), and the project's
own estimator (controller.tactile.estimator) as the reader of the rendered images.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest
from scipy.ndimage import map_coordinates

from controller.tactile import estimator_config, estimator_for_sensor
from controller.tactile.flow import make_grid_flow
from core.sensor_profile import sensor_profile
from drivers.sim.render.field_grid import GridUpsampler
from drivers.sim.render.field_inverse import MARGIN_PX, BackwardMapper
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.render.marker_images import (
    MarkerImageRenderer,
    area_mean_field,
    smooth_random_field,
)
from tests.drivers.sim.effects import ALL

HW = (240, 320)
# 5 px cells (a physics grid), 4 px, 16/3 px (not a whole number of pixels), full resolution
GRIDS = [(48, 64), (60, 80), (45, 60), HW]


def nodes_px(grid_hw, image_hw=HW):
    """Node positions (x, y) px of a grid in the pixel-centre convention, (h, w, 2)."""
    (h, w), (height, width) = grid_hw, image_hw
    xs = (np.arange(w) + 0.5) * width / w - 0.5
    ys = (np.arange(h) + 0.5) * height / h - 0.5
    return np.stack(np.meshgrid(xs, ys), axis=2)


A = np.array([[0.012, -0.008], [0.006, -0.010]])  # px per px
T = np.array([1.3, -0.7])  # px at the image centre
CENTRE = np.array([159.5, 119.5])


def affine_field(grid_hw):
    """u(p) = A (p - c) + t sampled on the grid's nodes, (h, w, 2) float32 px."""
    return ((nodes_px(grid_hw) - CENTRE) @ A.T + T).astype(np.float32)


def affine_inverse():
    """The exact backward map of the affine field: x + A (x - c) + t = y, (H, W, 2) px."""
    pixels = nodes_px(HW)
    return np.linalg.solve(np.eye(2) + A, (pixels + CENTRE @ A.T - T).reshape(-1, 2).T).T.reshape(
        pixels.shape
    )


def smooth_grid(grid_hw, amplitude_px, seed):
    full = smooth_random_field(HW, amplitude_px, np.random.default_rng(seed))
    return cv2.resize(full, grid_hw[::-1], interpolation=cv2.INTER_AREA)


# -- the field convention --------------------------------------------------------------------


@pytest.mark.parametrize("grid_hw", GRIDS)
def test_uniform_and_affine_fields_invert_exactly_at_any_resolution(grid_hw):
    mapper = BackwardMapper(HW)
    uniform = np.broadcast_to(T.astype(np.float32), (*grid_hw, 2))
    np.testing.assert_allclose(mapper(uniform), nodes_px(HW) - T, atol=1e-4)
    # a node-placement error of a fraction of a cell would show as |A| x offset >= 0.005 px
    np.testing.assert_allclose(mapper(affine_field(grid_hw)), affine_inverse(), atol=1e-3)


def test_coarse_and_full_resolution_fields_render_the_same_image():
    renderer = GelRenderer(rng=np.random.default_rng(1))
    for field_of in (lambda hw: np.broadcast_to(T.astype(np.float32), (*hw, 2)), affine_field):
        full = renderer.render(field_of(HW)).astype(int)
        for grid_hw in GRIDS[:3]:
            difference = np.abs(renderer.render(field_of(grid_hw)) - full)
            assert difference.max() <= 1 and difference.mean() < 0.01


def slow_inverse(field_in_margin, iterations=12):
    """Reference: x <- y - u(x) on every pixel, u bilinear at float precision on the field
    given at every pixel and MARGIN_PX around the image."""
    pixels = nodes_px(HW)
    x = pixels.copy()
    for _ in range(iterations):
        at = [x[..., 1] + MARGIN_PX, x[..., 0] + MARGIN_PX]
        u = [map_coordinates(field_in_margin[..., c], at, order=1, mode="nearest") for c in (0, 1)]
        x = pixels - np.stack(u, axis=2)
    return x


@pytest.mark.parametrize("grid_hw", GRIDS)
def test_the_map_inverts_the_upsampled_field(grid_hw):
    field = smooth_grid(grid_hw, 3.0, seed=4)
    exact = slow_inverse(GridUpsampler(grid_hw, HW, MARGIN_PX)(field))
    assert np.abs(BackwardMapper(HW)(field) - exact).max() < 5e-3


def test_misshapen_fields_are_refused():
    renderer = GelRenderer()
    for bad, match in [
        (np.zeros((320, 240, 2)), "aspect"),
        (np.zeros((48, 64, 3)), r"\(h, w, 2\)"),
        (np.zeros((1, 1, 2)), r"\(h, w, 2\)"),
        (np.full((48, 64, 2), np.nan), "finite"),
    ]:
        with pytest.raises(ValueError, match=match):
            renderer.render(bad)


# -- the look and the exact mode -------------------------------------------------------------


def test_same_gel_as_the_exact_renderer_and_nearly_the_same_warp():
    fast = GelRenderer(rng=np.random.default_rng(3))
    exact = MarkerImageRenderer(rng=np.random.default_rng(3))
    np.testing.assert_array_equal(fast.render(), exact.render())
    field = smooth_random_field(HW, 2.0, np.random.default_rng(1))
    difference = np.abs(fast.render(field).astype(int) - exact.render(field))
    assert difference.mean() < 0.5  # bilinear on the 1/2 px spline table: marker edges differ
    image = fast.render(field)
    assert image.dtype == np.uint8 and image.shape == (*HW, 3)


# -- determinism -----------------------------------------------------------------------------


def test_images_depend_only_on_seed_inputs_and_frame_index():
    field, start = smooth_grid((48, 64), 2.0, 5), smooth_grid((48, 64), 1.0, 6)

    def frame(seed, index, warm_up=()):
        renderer = GelRenderer(effects=ALL, rng=np.random.default_rng(seed))
        for earlier in warm_up:
            renderer.render(field, frame_index=earlier, drift=0.3)
        return renderer.render(field, frame_index=index, drift=0.5, exposure_start_px=start)

    first = frame(7, 3)
    np.testing.assert_array_equal(first, frame(7, 3, warm_up=(0, 1, 2, 5)))
    assert not np.array_equal(first, frame(7, 4))
    assert not np.array_equal(first, frame(8, 3))


def test_a_gel_kept_from_the_last_render_gives_the_frames_of_a_fresh_renderer():
    """The renderer keeps the last fields' gel (warped, occluded, blurred) and reuses it when
    the next fields are equal: frames are bit for bit a fresh renderer's, repeated, changed,
    absent and motion-blurred fields alike, and a field changed in place is not taken for
    the one kept."""
    press, other = smooth_grid((48, 64), 2.0, 5), smooth_grid((48, 64), 1.0, 6)
    changed = press.copy()
    calls = [(press, None), (press, None), (None, None), (None, None), (other, press)]
    calls += [(other, press), (changed, None), (changed, None)]
    kept = GelRenderer(effects=ALL, rng=np.random.default_rng(7))
    for index, (field, start) in enumerate(calls):
        if index == len(calls) - 1:
            changed += 0.25  # the array of the call before, new values
        drift = 0.1 * index
        frame = kept.render(field, frame_index=index, drift=drift, exposure_start_px=start)
        fresh = GelRenderer(effects=ALL, rng=np.random.default_rng(7))
        expected = fresh.render(field, frame_index=index, drift=drift, exposure_start_px=start)
        np.testing.assert_array_equal(frame, expected)


# -- effects ---------------------------------------------------------------------------------


def test_noise_has_the_requested_std_and_changes_every_frame():
    clean = GelRenderer(rng=np.random.default_rng(2)).render().astype(float)
    noisy = GelRenderer(effects=ImageEffects(noise_grey=4.0), rng=np.random.default_rng(2))
    frames = [noisy.render(frame_index=k).astype(float) - clean for k in range(3)]
    for noise in frames:
        assert noise.std() == pytest.approx(4.0, rel=0.05) and abs(noise.mean()) < 0.1
    correlation = np.corrcoef(frames[0].ravel(), frames[1].ravel())[0, 1]
    assert abs(correlation) < 0.05


def test_drift_moves_each_channel_mean_monotonically():
    effects = ImageEffects(drift_gain_per_level=(0.05, -0.04, 0.0))
    renderer = GelRenderer(effects=effects)
    means = np.array([renderer.render(drift=d).mean(axis=(0, 1)) for d in (0.0, 0.5, 1.0, 1.5)])
    steps = np.diff(means, axis=0)
    assert np.all(steps[:, 0] > 1) and np.all(steps[:, 1] < -1)  # B up, G down
    assert np.all(np.abs(steps[:, 2]) < 0.01)  # R: no gain drift


def test_drift_gradient_brightens_the_edge_it_points_to():
    angle = np.pi / 2  # toward +y: the bottom edge
    effects = ImageEffects(drift_gradient_grey_per_level=10.0, drift_gradient_angle_rad=angle)
    renderer = GelRenderer(effects=effects)
    change = renderer.render(drift=1.0).astype(float) - renderer.render()
    assert change[-5:].mean() > 6 and change[:5].mean() < -6  # 10 x reflectance (< 1)
    assert abs(change[:, :5].mean() - change[:, -5:].mean()) < 0.5  # nothing along x


def test_blur_is_a_gaussian_blur_of_the_image():
    field = smooth_grid((48, 64), 1.5, 7)
    sharp = GelRenderer(rng=np.random.default_rng(4)).render(field)
    blurred = GelRenderer(effects=ImageEffects(blur_sigma_px=1.5), rng=np.random.default_rng(4))
    expected = cv2.GaussianBlur(sharp.astype(np.float32), (0, 0), 1.5)
    difference = np.abs(blurred.render(field) - expected)
    assert difference.mean() < 0.6  # blur acts before the smooth shading, rounding differs
    assert np.abs(sharp - expected).mean() > 5 * difference.mean()


def test_motion_blur_is_the_mean_of_the_warps_over_the_exposure():
    start, end = smooth_grid((48, 64), 1.0, 8), smooth_grid((48, 64), 3.0, 9)
    effects = ImageEffects(motion_blur_samples=2)
    blurred = GelRenderer(effects=effects, rng=np.random.default_rng(4))
    plain = GelRenderer(rng=np.random.default_rng(4))
    ends = (plain.render(start).astype(float) + plain.render(end)) / 2
    assert np.abs(blurred.render(end, exposure_start_px=start) - ends).max() <= 1.0
    # a gel at rest during the exposure is not blurred
    np.testing.assert_array_equal(blurred.render(end, exposure_start_px=end), plain.render(end))
    np.testing.assert_array_equal(blurred.render(end), plain.render(end))
    with pytest.raises(ValueError, match="shape"):
        blurred.render(end, exposure_start_px=np.zeros((240, 320, 2)))


def test_marker_dropout_removes_that_fraction_of_markers_from_every_image():
    printed = GelRenderer(rng=np.random.default_rng(6))
    effects = ImageEffects(marker_dropout_fraction=0.3)
    worn = GelRenderer(effects=effects, rng=np.random.default_rng(6))
    n = len(printed.marker_centres_px)
    assert len(worn.dropped_marker_centres_px) == round(0.3 * n)
    assert len(worn.marker_centres_px) + len(worn.dropped_marker_centres_px) == n
    both = np.concatenate([worn.marker_centres_px, worn.dropped_marker_centres_px])
    np.testing.assert_array_equal(np.sort(both, axis=0), np.sort(printed.marker_centres_px, axis=0))

    def darkness_at(image, centres):
        grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(float)
        ij = np.rint(centres[:, ::-1]).astype(int).clip(0, np.array(HW) - 1)
        return grey[ij[:, 0], ij[:, 1]]

    for image in (worn.render(), worn.render(smooth_grid((48, 64), 0.3, 3))):
        present = darkness_at(image, worn.marker_centres_px)
        gone = darkness_at(image, worn.dropped_marker_centres_px)
        assert present.max() < 0.6 * gone.min()


def test_occluded_blobs_stay_put_while_the_gel_moves():
    effects = ImageEffects(occlusion_count=2, occlusion_size_px=30.0, noise_grey=2.0)
    renderer = GelRenderer(effects=effects, rng=np.random.default_rng(9))
    covered = renderer.occlusion_alpha > 0.9999
    assert 1500 < covered.sum() < 2 * np.pi * 30**2  # two ellipses, semi-axes 15-30 px
    images = [renderer.render(f, frame_index=1) for f in (None, smooth_grid((48, 64), 3.0, 1))]
    np.testing.assert_array_equal(images[0][covered], images[1][covered])
    free = renderer.occlusion_alpha < 1e-4
    assert np.abs(images[0][free].astype(int) - images[1][free]).mean() > 5


def test_effects_are_validated_with_the_key_named():
    with pytest.raises(ValueError, match="noise_grey"):
        ImageEffects(noise_grey=-1.0)
    with pytest.raises(ValueError, match="drift_gain_per_level"):
        ImageEffects(drift_gain_per_level=(0.1, 0.1))
    with pytest.raises(ValueError, match="motion_blur_samples"):
        ImageEffects(motion_blur_samples=0)
    with pytest.raises(ValueError, match="marker_dropout_fraction"):
        dataclasses.replace(ALL, marker_dropout_fraction=1.5)
    with pytest.raises(ValueError, match="frame_index"):
        GelRenderer(effects=ImageEffects(noise_grey=1.0)).render(frame_index=-1)


# -- the estimator reads the truth -------------------------------------------------------------


@pytest.mark.parametrize("effects", [ImageEffects(), ImageEffects(noise_grey=2.0)])
def test_the_estimator_recovers_the_area_mean_of_a_coarse_field(effects):
    profile = sensor_profile("gelsight_mini")
    renderer = GelRenderer(effects=effects, rng=np.random.default_rng(12))
    for index, amplitude in enumerate((1.0, 2.0), start=1):
        field = smooth_grid((48, 64), amplitude, seed=20 + index)
        estimator = estimator_for_sensor(profile, "default")
        estimator.set_reference(renderer.render(frame_index=0))
        estimator.push(renderer.render(field, frame_index=index), 0.0)
        grid = estimator.field
        measured = np.stack([grid.u_mm, grid.v_mm], axis=2) / profile.mm_per_px
        rows, cols = measured.shape[:2]
        truth = area_mean_field(GridUpsampler((48, 64), HW)(field), rows, cols)
        assert np.sqrt(((measured - truth) ** 2).sum(-1).mean()) < 0.1


def test_optical_flow_is_as_accurate_on_fast_renders_as_on_exact_ones():
    rng = np.random.default_rng(11)
    warps = [smooth_random_field(HW, amplitude, rng) for amplitude in (0.1, 0.5, 2.0)]

    def flow_errors(renderer):
        flow = make_grid_flow(estimator_config("default").flow, HW, 12, 16)
        flow.set_reference(renderer.render())
        out = np.empty((12, 16, 2))
        errors = []
        for field in warps:
            flow.measure(renderer.render(field), out)
            errors.append(np.sqrt(((out - area_mean_field(field, 12, 16)) ** 2).sum(-1).mean()))
        return np.array(errors)

    fast = flow_errors(GelRenderer(rng=np.random.default_rng(3)))
    exact = flow_errors(MarkerImageRenderer(rng=np.random.default_rng(3)))
    # OpenCV's bicubic remap adds up to 0.05 px here, bilinear on the image's pixels 0.008 px
    assert np.all(fast < exact + 0.004), (fast, exact)
