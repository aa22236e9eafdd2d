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
_DIAGONAL = np.diag_indices(3)
_SHEAR_UNITS = np.array([1.0, 1.0, 1e-6])  # (s_x, s_y in m, phi in rad): phi x 1 mm


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

    def energy_change(before: np.ndarray):
        """E(v + dv) - E(v) from the closure ``before`` at v (see ``_backtrack``)."""

        def change(dv: np.ndarray) -> float:
            closing = dv @ basis
            after = before + closing
            squares = np.where(
                (before > 0) & (after > 0),
                closing * (before + after),
                np.maximum(after, 0.0) ** 2 - np.maximum(before, 0.0) ** 2,
            )
            return 0.5 * float(k @ squares) - float(target @ dv)

        return change

    weighted_basis = basis * k
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
        hessian = (weighted_basis * active) @ basis.T
        hessian[_DIAGONAL] += 1e-12 * (hessian[0, 0] + hessian[1, 1] + hessian[2, 2])
        step = np.linalg.solve(hessian, -residual)
        v = _backtrack(energy_change(closure), v, step, residual)
    force_n = np.zeros_like(stiffness_n_m)
    force_n[cells] = force if balanced else k * np.maximum(v @ basis - sag, 0.0)
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
    # Sticking cells are linear (force -k g): their share of the generalized force and
    # stiffness is the all-stick stiffness less the other cells' share, so each iteration
    # handles per cell only the few cells that slip.
    moments = _moment_basis(x, y)
    all_stick = _stick_stiffness(k, moments)
    reach = limit / k  # the longest elastic slide of each cell, m

    def slide(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return v[0] - v[2] * y, v[1] + v[2] * x

    def energy_change(v, gx, gy, g, slip):
        """E(v + dv) - E(v) given the slide ``gx, gy``, its length ``g`` and the slipping
        cells at v (see ``_backtrack``)."""

        def change(dv: np.ndarray) -> float:
            dgx, dgy = slide(dv)
            hx, hy = gx + dgx, gy + dgy
            h = _length(hx, hy)
            moved = np.flatnonzero(slip | (k * h > limit))  # not sticking throughout
            sticking = all_stick - _stick_stiffness(k[moved], moments[:, moved])
            stuck = float(v @ sticking @ dv) + 0.5 * float(dv @ sticking @ dv)
            # The cell energy is L u - L^2 / 2k + k/2 max(L/k - u, 0)^2 at slide length u:
            # 0.5 k u^2 below the limit, L u - L^2 / 2k beyond it.
            g_m, h_m, reach_m = g[moved], h[moved], reach[moved]
            squares = dgx[moved] * (gx + hx)[moved] + dgy[moved] * (gy + hy)[moved]
            longer = squares / (g_m + h_m)  # |h| - |g| without cancellation
            below = np.maximum(reach_m - h_m, 0.0) ** 2 - np.maximum(reach_m - g_m, 0.0) ** 2
            per_cell = limit[moved] * longer + 0.5 * k[moved] * below
            return stuck + float(per_cell.sum()) + float(target @ dv)

        return change

    if start is None:
        v = np.linalg.solve(all_stick, -target)
    else:
        v = start.copy()
    capacity = float(limit.sum())
    squared_radius = moments[3] + moments[4]
    radius = float(np.sqrt(squared_radius.mean())) + 1e-9  # RMS, m
    size = max(float(np.abs(target[:2]).sum() + np.abs(target[2]) / radius), 1e-12)
    tolerance = TOLERANCE * size * np.array([1, 1, radius])
    # Beyond reach: the slide is far beyond the largest elastic one, no minimum exists.
    beyond_reach = 1e3 * float(reach.max())
    extent = float(np.sqrt(squared_radius.max()))
    gross = False
    for _ in range(NEWTON_ITERATIONS):
        gx, gy = slide(v)
        g = _length(gx, gy)
        slip = k * g > limit
        slipping_cells = np.flatnonzero(slip)
        sticking = all_stick - _stick_stiffness(k[slipping_cells], moments[:, slipping_cells])
        # A slipping cell pulls with L along -g; its stiffness is (L/|g|)(I - n n^T).
        pull = limit[slipping_cells]
        length = g[slipping_cells]
        nx, ny = gx[slipping_cells] / length, gy[slipping_cells] / length
        sums = np.stack([pull * nx, pull * ny]) @ moments[:3, slipping_cells].T
        slipping_force = -np.array([sums[0, 0], sums[1, 0], sums[1, 1] - sums[0, 2]])
        residual = slipping_force - sticking @ v - target
        if np.all(np.abs(residual) <= tolerance):
            break
        if slip.all() or abs(v[0]) + abs(v[1]) + abs(v[2]) * extent > beyond_reach:
            gross = True
            break
        a = pull / length
        hessian = sticking + _stiffness(
            a - a * nx * nx, a - a * ny * ny, -a * nx * ny, moments[:, slipping_cells]
        )
        hessian[_DIAGONAL] += 1e-9 * (hessian[0, 0] + hessian[1, 1] + hessian[2, 2]) * _SHEAR_UNITS
        step = np.linalg.solve(hessian, residual)
        v = _backtrack(energy_change(v, gx, gy, g, slip), v, step, -residual)
    else:
        gross = bool(slip.all()) or capacity < np.hypot(*target[:2])
        gx, gy = slide(v)  # where the last step went
        g = _length(gx, gy)
        slip = k * g > limit
    if gross:
        g = np.maximum(g, 1e-30)
        fx, fy, slip = -limit * gx / g, -limit * gy / g, np.ones_like(slip)
        v = np.full(3, np.nan)  # the object slides: its place is the scene's business
    else:
        scale = np.where(slip, limit / np.maximum(g, 1e-30), k)
        fx, fy = -scale * gx, -scale * gy
    force_n[..., 0][cells], force_n[..., 1][cells] = fx, fy  # (not [cells, 0]: 20x slower)
    slipping[cells] = slip
    return TangentialContact(force_n, slipping, v, gross)


def _moment_basis(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per cell (1, x, y, x^2, y^2, x y), (6, n): its product with a weight per cell gives
    the weight's moments."""
    moments = np.empty((6, x.size))
    moments[0], moments[1], moments[2] = 1.0, x, y
    np.multiply(x, x, out=moments[3])
    np.multiply(y, y, out=moments[4])
    np.multiply(x, y, out=moments[5])
    return moments


def _stiffness(kxx, kyy, kxy, moments: np.ndarray) -> np.ndarray:
    """Sum over cells of J^T K J in (s_x, s_y, phi): K = [[kxx, kxy], [kxy, kyy]] per cell
    and the slide g = J v, J = [[1, 0, -y], [0, 1, x]]."""
    a, b, c = np.stack([kxx, kyy, kxy]) @ moments.T
    h02, h12 = c[1] - a[2], b[1] - c[2]
    return np.array([[a[0], c[0], h02], [c[0], b[0], h12], [h02, h12, a[4] - 2 * c[5] + b[3]]])


def _stick_stiffness(k: np.ndarray, moments: np.ndarray) -> np.ndarray:
    """``_stiffness`` of sticking cells, K = k I."""
    m = moments @ k
    return np.array([[m[0], 0.0, -m[2]], [0.0, m[0], m[1]], [-m[2], m[1], m[3] + m[4]]])


def _length(gx: np.ndarray, gy: np.ndarray) -> np.ndarray:
    """Per cell |(gx, gy)|: sqrt of the sum of squares, several times faster than np.hypot
    (whose overflow guard slides of micrometres do not need)."""
    return np.sqrt(gx * gx + gy * gy)


def _backtrack(energy_change, v: np.ndarray, step: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """The Newton step, halved until the energy decreases enough (Armijo).

    ``energy_change(dv)`` is ``E(v + dv) - E(v)`` in a form without cancellation (summed per
    cell, or as a quadratic form for the linear cells): near the minimum the decrease a step
    buys is far below the rounding error of ``E`` itself, and comparing two energies there
    rejects good steps at random.
    """
    slope, t = float(gradient @ step), 1.0
    for _ in range(30):
        if energy_change(t * step) <= 1e-4 * t * slope:
            return v + t * step
        t *= 0.5
    return v + t * step
