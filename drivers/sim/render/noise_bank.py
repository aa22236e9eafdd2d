"""Seeded Gaussian pixel noise per frame index, without drawing a frame's worth of normals.

Drawing 320 x 240 x 3 normals with NumPy takes about 1.5 ms, most of a frame's render budget.
Instead a ``NoiseBank`` draws ``BANK_FRAMES`` noise images once, each ``MARGIN_PX`` larger
than the frame along both axes, and frame ``k`` uses a window of one of them at an offset,
both picked from a ``SeedSequence`` of (the bank's seed, k). So a frame's noise depends only
on (seed, k), not on which frames were rendered before, and costs nothing to draw.

The price: frames are not fully independent. Two frames share noise values only if they pick
the same bank image; then their noise is the same pattern shifted by the difference of their
offsets, identical for a probability of 1 / (BANK_FRAMES * MARGIN_PX**2) (1 in 9216) per pair,
and shifted by at most 2 px along both axes (which dense optical flow could follow) for about
1 in 370 pairs.
"""

from __future__ import annotations

import numpy as np

BANK_FRAMES = 4
MARGIN_PX = 48


class NoiseBank:
    """Gaussian noise of ``sigma_grey`` grey levels for (H, W, C) frames; ``seed`` is any
    NumPy seed (an int or a SeedSequence)."""

    def __init__(
        self, shape: tuple[int, int, int], sigma_grey: float, seed: int | np.random.SeedSequence
    ) -> None:
        height, width, channels = shape
        sequence = (
            seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
        )
        bank_seed, frame_seed = sequence.spawn(2)
        self._key = int(frame_seed.generate_state(1, np.uint64)[0])
        bank = np.random.default_rng(bank_seed).standard_normal(
            (BANK_FRAMES, height + MARGIN_PX, width + MARGIN_PX, channels), dtype=np.float32
        )
        self._bank = bank * np.float32(sigma_grey)
        self.shape = shape

    def frame(self, index: int) -> np.ndarray:
        """The noise of frame ``index`` (>= 0): a read-only float32 (H, W, C) view, grey levels."""
        if isinstance(index, bool) or not isinstance(index, int | np.integer) or index < 0:
            raise ValueError(f"frame_index: expected an integer >= 0, got {index!r}")
        words = np.random.SeedSequence((self._key, index)).generate_state(3)
        image, dy, dx = (int(v) for v in words % (BANK_FRAMES, MARGIN_PX, MARGIN_PX))
        height, width = self.shape[:2]
        window = self._bank[image, dy : dy + height, dx : dx + width]
        window.flags.writeable = False
        return window
