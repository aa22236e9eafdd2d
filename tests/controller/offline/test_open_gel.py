"""The open gel's check (estimate --open): camera noise and exposure are no change."""

import numpy as np

from controller.offline.open_gel import TOLERANCE_GREY, change_grey, open_gel_doubt
from drivers.sim.render.marker_images import MarkerImageRenderer


def test_noise_and_exposure_pass_and_a_shift_of_the_markers_does_not():
    rng = np.random.default_rng(1)
    gel = MarkerImageRenderer(rng=np.random.default_rng(5)).render().astype(float)

    def camera(image, gain=1.0, sigma=6.0):
        return np.clip(gain * image + rng.normal(0, sigma, image.shape), 0, 255).astype(np.uint8)

    frames = [camera(gel), camera(gel, gain=1.15), camera(gel + 12)]
    assert open_gel_doubt(frames, 10, (0, camera(gel))) is None
    shifted = camera(np.roll(gel, 1, axis=1))  # every marker one pixel to the right
    assert change_grey(shifted, frames[0]) > 2 * TOLERANCE_GREY
    assert open_gel_doubt(frames, 10, (0, shifted)).startswith("frame 0 differs from frame 10")
