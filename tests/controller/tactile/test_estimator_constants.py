"""The estimator's per-grid constants are built once per process and shared (the Green's
spectrum and matrix, the membrane prior, the pixel grid, the fallback dipole's divergence
map): estimates made with the shared constants are bit for bit those made with constants
built afresh, on a rendered press-and-tilt sequence, on both zeroing paths (the grasp's
support from the open gel, and the noise-gated fallback without it)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from controller.tactile import TactileEstimator, estimator_for_sensor
from controller.tactile import estimator as estimator_module
from controller.tactile.grid_lk import grid_prior, pixel_grid
from controller.tactile.nhhd import greens_kernel, greens_matrix, greens_spectrum
from controller.tactile.settings import DipoleGrid, estimator_config
from core.sensor_profile import sensor_profile
from drivers.sim.render.gel_renderer import GelRenderer
from drivers.sim.render.image_effects import ImageEffects
from drivers.sim.scenes.synthetic_sequence import phase_patterns

PATTERNS = phase_patterns((240, 320), peak_px=1.5)


def _frames() -> list[np.ndarray]:
    """A noisy rendered sequence: 3 open-gel frames, a press, a tilt growing both ways."""
    renderer = GelRenderer(effects=ImageEffects(noise_grey=2.0), rng=np.random.default_rng(8))
    press = 0.6 * PATTERNS["shear"] + 0.8 * PATTERNS["twist"]
    fields = [None] * 3 + [press] * 3
    fields += [press + a * PATTERNS["tilt_x"] for a in (0.3, 0.6, 1.0, -0.5)]
    return [renderer.render(f, frame_index=k) for k, f in enumerate(fields)]


def _forget_constants() -> None:
    for cached in (greens_spectrum, greens_matrix, grid_prior, pixel_grid):
        cached.cache_clear()
    estimator_module._DIVERGENCE_MAPS.clear()


def _estimates(frames: list[np.ndarray], open_gel: bool) -> list[tuple]:
    estimator = estimator_for_sensor("gelsight_mini")
    if open_gel:
        estimator.capture_open(3)
    out = []
    for k, frame in enumerate(frames):
        if k == 3:
            estimator.rezero(3)
        out.append(dataclasses.astuple(estimator.push(frame, 0.04 * k)))
    assert estimator.noise_gated != open_gel  # each path taken
    return out


@pytest.mark.parametrize("open_gel", [True, False])
def test_shared_constants_give_the_estimates_of_fresh_ones(open_gel):
    frames = _frames()
    _forget_constants()
    fresh = _estimates(frames, open_gel)
    shared = _estimates(frames, open_gel)  # every constant now comes from the first run
    assert shared == fresh
    assert any(e[1] != 0.0 for e in fresh)  # the tilt was estimated, not zero throughout


def test_the_constants_are_read_only_and_equal_to_their_direct_construction():
    spectrum = greens_spectrum(12, 16, 1.27, 1.27)
    matrix = greens_matrix(4, 4, 5.07, 3.8)
    assert not spectrum.flags.writeable and not matrix.flags.writeable
    np.testing.assert_array_equal(
        spectrum, np.fft.rfft2(greens_kernel(12, 16, 1.27, 1.27)) * (1.27 * 1.27)
    )
    kernel = greens_kernel(4, 4, 5.07, 3.8) * (5.07 * 3.8)
    assert matrix[5, 6] == kernel[0, (1 - 2) % 8]  # cell (1, 1) from cell (1, 2)
    assert matrix[0, 15] == kernel[(0 - 3) % 8, (0 - 3) % 8]


def test_each_configuration_has_its_own_divergence_map():
    """The map is shared by configuration and grid: a 4 x 3 fallback dipole grid does not
    get the 4 x 4 grid's map (12 rows against 16)."""
    frame = _frames()[0]
    _forget_constants()
    shapes = set()
    for rows in (4, 3):
        config = dataclasses.replace(
            estimator_config("default"), dipole_grid=DipoleGrid(cols=4, rows=rows)
        )
        estimator = TactileEstimator(config, sensor_profile("gelsight_mini"))
        estimator.set_reference(frame)
        assert estimator.noise_gated
        shapes |= {m.shape for m in estimator_module._DIVERGENCE_MAPS.values()}
    assert shapes == {(16, 2 * 192), (12, 2 * 192)}
