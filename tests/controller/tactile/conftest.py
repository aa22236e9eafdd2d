import numpy as np
import pytest

from drivers.sim.render.marker_images import MarkerImageRenderer


@pytest.fixture(scope="session")
def renderer() -> MarkerImageRenderer:
    return MarkerImageRenderer(rng=np.random.default_rng(3))
