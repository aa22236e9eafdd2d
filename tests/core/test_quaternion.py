"""core/quaternion.py and the quaternion forms of core/spatial.py against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from core import quaternion as q
from core.spatial import (
    quat_from_rpy,
    rotation_from_rpy,
    rpy_from_quat,
    rpy_from_rotation,
    tilt_of_quat,
    tilt_of_tool_axis,
    tool_z_in_base,
)


def same_rotation(a, b) -> bool:
    return bool(np.isclose(abs(np.dot(a, b)), 1.0, atol=1e-12))


@pytest.mark.parametrize("seed", range(5))
def test_the_closed_forms_agree_with_scipy(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        rpy = (*rng.uniform(-3.1, 3.1, 1), *rng.uniform(-1.5, 1.5, 1), *rng.uniform(-3.1, 3.1, 1))
        near = tuple(np.array(rpy) + rng.uniform(-1.0, 1.0, 3))
        r, a = rotation_from_rpy(rpy), quat_from_rpy(rpy)
        assert same_rotation(a, r.as_quat())
        assert np.allclose(rpy_from_quat(a, near), rpy_from_rotation(r, near), atol=1e-9)
        assert np.allclose(q.z_axis(a), r.as_matrix()[:, 2], atol=1e-12)
        tilt, axis = tilt_of_quat(a)
        expected_tilt, expected_axis = tilt_of_tool_axis(tool_z_in_base(r))
        assert tilt == pytest.approx(expected_tilt, abs=1e-9)
        assert np.allclose(axis, expected_axis, atol=1e-9)
        v = rng.normal(size=3) * rng.uniform(0.0, 3.0)
        b, rb = q.from_rotvec(tuple(v)), Rotation.from_rotvec(v)
        assert same_rotation(b, rb.as_quat())
        assert np.allclose(q.rotvec(q.multiply(b, a)), (rb * r).as_rotvec(), atol=1e-9)
        assert np.allclose(
            q.rotvec(q.multiply(a, q.inverse(b))), (r * rb.inv()).as_rotvec(), atol=1e-9
        )


def test_small_and_straight_cases():
    assert q.from_rotvec((0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0, 1.0)
    assert q.rotvec((0.0, 0.0, 0.0, 1.0)) == (0.0, 0.0, 0.0)
    tiny = (1e-10, -2e-10, 3e-10)
    assert np.allclose(q.rotvec(q.from_rotvec(tiny)), tiny, rtol=1e-9, atol=0)
    down = quat_from_rpy((np.pi, 0.0, 0.3))
    assert tilt_of_quat(down) == (pytest.approx(0.0, abs=1e-12), (0.0, 0.0, 0.0))
    # at pitch +-pi/2 scipy's rule decides (its gimbal-lock warning is expected there)
    with pytest.warns(UserWarning, match="Gimbal lock"):
        locked = rpy_from_quat(quat_from_rpy((0.2, np.pi / 2, 0.1)))
    assert same_rotation(quat_from_rpy(locked), quat_from_rpy((0.2, np.pi / 2, 0.1)))
    assert q.normalised((0.0, 0.0, 0.0, 2.0)) == (0.0, 0.0, 0.0, 1.0)
