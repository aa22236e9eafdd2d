"""Quasi-static contact between a rigid object and the gel layer (SI: m, N, N*m, Pa).

Both problems are solved per cell of the physics grid (``drivers.sim.gel.footprint``), with
the thin-layer (Winkler) stiffness of the layer, and each is the minimum of a convex energy
in three rigid-body unknowns, found by Newton's method with a backtracking line search.

**Normal.** The object's face moves toward the gel by ``delta(x, y) = d0 + a y + b x``; a
cell closes by ``delta - sag`` and carries the force ``F = k_n A w_edge max(delta - sag, 0)``
(no tension: where the face would pull, it lifts off). The unknowns balance the normal
load ``N`` (the grip plus the wrench's fz) and the tilt torques of the wrench the gel exerts
on the object: ``sum F = N``, ``sum F y = tau_x``, ``-sum F x = tau_y`` (S: z points from
the camera toward the object, so the gel pushes the object along +z).

**Tangential** (brush model with Coulomb friction). The object slides over the gel's base
by ``g(x, y) = (s_x - phi y, s_y + phi x)``; a cell pulls it back by ``-k_t A g`` until that
reaches the friction limit ``mu F``, beyond which the cell slips and pulls with ``mu F``
against ``g``. The unknowns balance the wrench's in-plane part: ``sum f = (f_x, f_y)``,
``sum (x f_y - y f_x) = tau_z``. Since the limit ``mu F`` falls to zero at the footprint's
edges (the edge weight) and ``|g|`` grows with the distance from the centre of rotation,
slip starts at the edges and spreads inward. When the load exceeds what friction can hold
the energy has no minimum: the contact slips as a whole (gross slip) and the tractions are
the friction limit along the last slip direction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NEWTON_ITERATIONS = 60
TOLERANCE = 1e-9  # relative residual of the balance equations


@dataclass(frozen=True)
class NormalContact:
    """``force_n``: normal force of each cell on the object, N (rows, cols);
    ``rigid``: (d0 in m, a, b) of the face's approach; ``balanced``: False when the tilt
    torque exceeded what the contact can hold (the face tips over its edge; ``rigid`` has
    then run off along the tip) or when a load was asked without a normal force to carry it."""

    force_n: np.ndarray
    rigid: np.ndarray
    balanced: bool


@dataclass(frozen=True)
class TangentialContact:
    """``force_n``: in-plane force of each cell on the object, N (rows, cols, 2);
    ``slipping``: cells at the friction limit; ``rigid``: (s_x, s_y in m, phi in rad), the
    object's in-plane displacement and rotation over the gel's base (NaN under gross slip);
    ``gross_slip``: the load exceeded friction."""

    force_n: np.ndarray
    slipping: np.ndarray
    rigid: np.ndarray
    gross_slip: bool


def solve_normal(
    x_m: np.ndarray,
    y_m: np.ndarray,
    sag_m: np.ndarray,
    stiffness_n_m: np.ndarray,
    load: tuple[float, float, float],
    start: np.ndarray | None = None,
) -> NormalContact:
    """Normal contact for ``load`` = (normal force N, tau_x, tau_y in N*m); cells with zero
    ``stiffness_n_m`` (N/m per cell) are outside the footprint. ``start``: a previous
    ``rigid`` to start from."""
    normal, tau_x, tau_y = load
    cells = stiffness_n_m > 0
    k = stiffness_n_m[cells]
    basis = np.stack([np.ones_like(k), y_m[cells], x_m[cells]])  # (3, n)
    sag = sag_m[cells]
    target = np.array([normal, tau_x, -tau_y])
    if normal <= 0 or k.size == 0:
        # No normal force to carry anything: balanced only if nothing was asked.
        return NormalContact(np.zeros_like(stiffness_n_m), np.zeros(3), not target.any())

    def energy_change(v: np.ndarray, dv: np.ndarray) -> float:
        before = v @ basis - sag
        closing = dv @ basis
        after = before + closing
        squares = np.where(
            (before > 0) & (after > 0),
            closing * (before + after),
            np.maximum(after, 0.0) ** 2 - np.maximum(before, 0.0) ** 2,
        )
        return 0.5 * float(k @ squares) - float(target @ dv)

    v = start.copy() if start is not None else np.array([sag.min() + normal / k.sum(), 0, 0])
    scale = max(abs(normal), 1e-12)
    lever = float(np.sqrt((basis[1:] ** 2).sum(axis=0).mean()))  # rms lever arm, m
    balanced = False
    for _ in range(NEWTON_ITERATIONS):
        closure = v @ basis - sag
        active = closure > 0
        force = k * np.maximum(closure, 0.0)
        residual = basis @ force - target
        if abs(residual[0]) <= TOLERANCE * scale and np.all(
            np.abs(residual[1:]) <= TOLERANCE * scale * lever
        ):
            balanced = True
            break
        if not active.any():
            v[0] += (normal / k.sum()) + (sag - v @ basis).min()
            continue
        weighted = basis[:, active] * k[active]
        hessian = weighted @ basis[:, active].T
        hessian += np.eye(3) * 1e-12 * np.trace(hessian)
        step = np.linalg.solve(hessian, -residual)
        v = _backtrack(energy_change, v, step, residual)
    force_n = np.zeros_like(stiffness_n_m)
    force_n[cells] = k * np.maximum(v @ basis - sag, 0.0)
    return NormalContact(force_n, v, balanced)


def solve_tangential(
    x_m: np.ndarray,
    y_m: np.ndarray,
    stiffness_n_m: np.ndarray,
    limit_n: np.ndarray,
    load: tuple[float, float, float],
    start: np.ndarray | None = None,
) -> TangentialContact:
    """Tangential contact for ``load`` = (f_x, f_y in N, tau_z in N*m), the in-plane wrench
    the gel exerts on the object; ``stiffness_n_m``: shear stiffness per cell (N/m);
    ``limit_n``: friction limit per cell (N), zero where the cell carries no pressure."""
    cells = limit_n > 0
    force_n = np.zeros((*limit_n.shape, 2))
    slipping = np.zeros(limit_n.shape, bool)
    target = np.asarray(load, float)
    if not cells.any():
        gross = bool(np.any(target != 0))
        return TangentialContact(force_n, slipping, np.zeros(3), gross_slip=gross)
    k, limit = stiffness_n_m[cells], limit_n[cells]
    x, y = x_m[cells], y_m[cells]

    def slide(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return v[0] - v[2] * y, v[1] + v[2] * x

    def elastic(g: np.ndarray) -> np.ndarray:
        return np.where(k * g <= limit, 0.5 * k * g**2, limit * g - 0.5 * limit**2 / k)

    def energy_change(v: np.ndarray, dv: np.ndarray) -> float:
        gx, gy = slide(v)
        dgx, dgy = slide(dv)
        hx, hy = gx + dgx, gy + dgy
        squares = dgx * (gx + hx) + dgy * (gy + hy)  # |h|^2 - |g|^2
        g, h = np.hypot(gx, gy), np.hypot(hx, hy)
        stick_before, stick_after = k * g <= limit, k * h <= limit
        change = np.where(
            stick_before & stick_after,
            0.5 * k * squares,
            np.where(
                ~stick_before & ~stick_after,
                limit * squares / np.maximum(g + h, 1e-30),
                elastic(h) - elastic(g),
            ),
        )
        return float(change.sum()) + float(target @ dv)

    def forces(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        gx, gy = slide(v)
        g = np.hypot(gx, gy)
        slip = k * g > limit
        scale = np.where(slip, limit / np.maximum(g, 1e-30), k)
        return -scale * gx, -scale * gy, slip

    if start is None:
        stick_hessian = _stick_hessian(k, x, y)
        v = np.linalg.solve(stick_hessian, -target)
    else:
        v = start.copy()
    capacity = float(limit.sum())
    size = max(float(np.abs(target[:2]).sum() + np.abs(target[2]) / _radius(x, y)), 1e-12)
    gross = False
    for _ in range(NEWTON_ITERATIONS):
        fx, fy, slip = forces(v)
        residual = np.array([fx.sum(), fy.sum(), (x * fy - y * fx).sum()]) - target
        if np.all(np.abs(residual) <= TOLERANCE * size * np.array([1, 1, _radius(x, y)])):
            break
        if slip.all() or _beyond_reach(v, x, y, k, limit):
            gross = True
            break
        hessian = _hessian(v, k, limit, x, y, slide)
        step = np.linalg.solve(hessian, residual)
        v = _backtrack(energy_change, v, step, -residual)
    else:
        gross = bool(slip.all()) or capacity < np.hypot(*target[:2])
    fx, fy, slip = forces(v)
    if gross:
        gx, gy = slide(v)
        g = np.maximum(np.hypot(gx, gy), 1e-30)
        fx, fy, slip = -limit * gx / g, -limit * gy / g, np.ones_like(slip)
        v = np.full(3, np.nan)  # the object slides: its place is the scene's business
    force_n[cells, 0], force_n[cells, 1] = fx, fy
    slipping[cells] = slip
    return TangentialContact(force_n, slipping, v, gross)


def _stick_hessian(k: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.array(
        [
            [k.sum(), 0.0, -(k * y).sum()],
            [0.0, k.sum(), (k * x).sum()],
            [-(k * y).sum(), (k * x).sum(), (k * (x * x + y * y)).sum()],
        ]
    )


def _hessian(v, k, limit, x, y, slide) -> np.ndarray:
    """Second derivative of the brush energy in (s_x, s_y, phi)."""
    gx, gy = slide(v)
    g = np.maximum(np.hypot(gx, gy), 1e-30)
    slip = k * g > limit
    # Per cell, the 2x2 stiffness: k I when sticking, (L/|g|)(I - n n^T) when slipping.
    a = np.where(slip, limit / g, k)
    nx, ny = gx / g, gy / g
    kxx = a - np.where(slip, a * nx * nx, 0.0)
    kyy = a - np.where(slip, a * ny * ny, 0.0)
    kxy = -np.where(slip, a * nx * ny, 0.0)
    # g = J v with J = [[1, 0, -y], [0, 1, x]].
    h = np.empty((3, 3))
    h[0, 0], h[1, 1], h[0, 1] = kxx.sum(), kyy.sum(), kxy.sum()
    h[0, 2] = (-kxx * y + kxy * x).sum()
    h[1, 2] = (-kxy * y + kyy * x).sum()
    h[2, 2] = (kxx * y * y - 2 * kxy * x * y + kyy * x * x).sum()
    h[1, 0], h[2, 0], h[2, 1] = h[0, 1], h[0, 2], h[1, 2]
    return h + np.eye(3) * 1e-9 * np.trace(h) * np.array([1, 1, 1e-6])


def _radius(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x * x + y * y))) + 1e-9


def _beyond_reach(v, x, y, k, limit) -> bool:
    """True once the slide is far beyond the largest elastic one: the energy has no minimum."""
    reach = float((limit / k).max())
    slide = abs(v[0]) + abs(v[1]) + abs(v[2]) * float(np.sqrt((x * x + y * y).max()))
    return slide > 1e3 * reach


def _backtrack(energy_change, v: np.ndarray, step: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """The Newton step, halved until the energy decreases enough (Armijo).

    ``energy_change(v, dv)`` is ``E(v + dv) - E(v)`` summed per cell in a form without
    cancellation: near the minimum the decrease a step buys is far below the rounding error
    of ``E`` itself, and comparing two energies there rejects good steps at random.
    """
    slope, t = float(gradient @ step), 1.0
    for _ in range(30):
        if energy_change(v, t * step) <= 1e-4 * t * slope:
            return v + t * step
        t *= 0.5
    return v + t * step
