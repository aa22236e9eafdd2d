"""Each flow method recovers known sub-pixel warps of a rendered marker-gel image."""

from dataclasses import replace

import numpy as np
import pytest

from controller.tactile.flow import DenseGridFlow, detect_markers, make_grid_flow
from controller.tactile.settings import estimator_config
from drivers.sim.render.marker_images import area_mean_field, smooth_random_field

ROWS, COLS = 12, 16
BASE = estimator_config("dis_half").flow
PAPER = estimator_config("paper").flow
GRID_LK = estimator_config("default").flow
# Tolerances: grid RMSE in px over warps with peak 0.1-3 px (docs/BENCHMARKS.md has the
# measured errors; these bounds leave about 2x headroom).
METHODS = {
    "dis_half": (BASE, 0.15),  # 8 px patches every 6 px: 0.086 px at the 3 px warp
    "paper_farneback_per_channel": (PAPER, 0.08),
    "dis_ultrafast": (
        replace(
            BASE,
            scale=1.0,
            dis=replace(
                BASE.dis,
                preset="ultrafast",
                use_mean_normalization=None,
                finest_scale=None,
                patch_size=None,
                patch_stride=None,
                gradient_descent_iterations=None,
                variational_refinement_iterations=None,
            ),
        ),
        0.25,
    ),
    "dis_medium_half_scale": (
        replace(BASE, scale=0.5, dis=replace(BASE.dis, preset="medium")),
        0.3,
    ),
    "farneback_gray_warm": (replace(PAPER, color="gray", warm_start=True), 0.08),
    "markers": (replace(BASE, method="markers"), 0.15),
    # Each warp here is a new random field, so the warm start (a frame-to-frame aid) is off.
    "grid_lk": (replace(GRID_LK, warm_start=False), 0.2),  # 0.093 px at the 3 px warp
}


@pytest.fixture(scope="module")
def warps(renderer):
    rng = np.random.default_rng(11)
    cases = []
    for amplitude in (0.1, 0.5, 1.0, 2.0, 3.0):
        field = smooth_random_field((240, 320), amplitude, rng)
        cases.append((renderer.render(field), area_mean_field(field, ROWS, COLS)))
    return cases


@pytest.mark.parametrize("name", METHODS)
def test_flow_recovers_subpixel_warps(name, renderer, warps):
    config, tolerance_px = METHODS[name]
    flow = make_grid_flow(config, (240, 320), ROWS, COLS)
    flow.set_reference(renderer.render())
    out = np.empty((ROWS, COLS, 2))
    errors = []
    for image, truth in warps:
        flow.measure(image, out)
        errors.append(np.sqrt(((out - truth) ** 2).sum(-1).mean()))
    assert max(errors) < tolerance_px, errors
    # not just small: at the largest warp the error is a small fraction of the signal
    assert errors[-1] < 0.15 * np.sqrt((warps[-1][1] ** 2).sum(-1).mean())


def test_identical_image_gives_zero_field(renderer):
    flow = make_grid_flow(BASE, (240, 320), ROWS, COLS)
    flow.set_reference(renderer.render())
    out = flow.measure(renderer.render(), np.empty((ROWS, COLS, 2)))
    assert np.abs(out).max() < 1e-3


def test_dense_flow_is_repeatable_without_warm_start(renderer, warps):
    flow = DenseGridFlow(BASE, (240, 320), ROWS, COLS)
    flow.set_reference(renderer.render())
    first = flow.measure(warps[2][0], np.empty((ROWS, COLS, 2))).copy()
    flow.measure(warps[4][0], np.empty((ROWS, COLS, 2)))
    again = flow.measure(warps[2][0], np.empty((ROWS, COLS, 2)))
    np.testing.assert_array_equal(first, again)


def test_marker_detection_finds_rendered_markers(renderer):
    import cv2

    gray = cv2.cvtColor(renderer.render(), cv2.COLOR_BGR2GRAY)
    found = detect_markers(gray, BASE.markers)
    truth = renderer.marker_centres_px
    margin = 10  # markers cut by the image border have biased centres
    x, y = truth[:, 0], truth[:, 1]
    inside = truth[(x > margin) & (x < 320 - margin) & (y > margin) & (y < 240 - margin)]
    assert len(inside) <= len(found) <= len(truth)
    nearest = np.min(np.hypot(*(found[:, None, :] - inside[None, :, :]).transpose(2, 0, 1)), axis=0)
    assert nearest.max() < 0.3  # sub-pixel centres


def test_markers_method_rejects_a_gel_without_markers():
    flat = np.full((240, 320, 3), 128, np.uint8)
    flow = make_grid_flow(replace(BASE, method="markers"), (240, 320), ROWS, COLS)
    with pytest.raises(ValueError, match="markers"):
        flow.set_reference(flat)
