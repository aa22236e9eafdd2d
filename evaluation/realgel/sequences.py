"""Tilt sequences on real gel textures, deformed by the half-space model (elastic.py).

A flat rectangular contact (the grasped object's face) presses on the gel with a uniform
grip pressure; tilting the object adds a linear pressure gradient across the contact
(along y for a tilt about x, along x for a tilt about y). At full tilt the gradient changes
the pressure at the contact's edges by ``TILT_RATIO`` of the grip pressure. Pushing makes
the grip pressure itself swing by +-``push`` (relative), so that at the extremes
(push 0.5 at full tilt) one edge just loses its pressure and no pressure is ever negative.

Every frame is the texture warped by the surface displacement of its pressure (backward
map: the inverse of the forward field, by fixed-point iteration, then ``cv2.remap`` with
bicubic interpolation and reflected borders), plus Gaussian camera noise, rounded to uint8.
With ``shading`` "moves" the whole capture is warped, LED shading included (the simple
choice); with "fixed" only its albedo is (markers and fine texture), under the capture's
illumination, which stays with the camera as a real sensor's LEDs do
(textures.split_illumination): harder, because a smooth gel's shading then carries no
motion and a marker moving through a shading gradient changes brightness.
The reference frame is the grasp without tilt (the estimator zeroes on it); before it, the
open frames show the capture unwarped (the gel before the grasp, same illumination, own
noise), which the estimator may use to locate the contact (every estimator gets them). Displacements
are scaled so that the tilt's own part of the field peaks at ``tilt_px`` pixels at full
tilt. The truth of each frame is the applied tilt torque (``elastic.PressureBasis``).

Seeded: the contact, the signals' phases and the noise follow from ``SequenceSpec.seed``;
the contact and the signals do not depend on the texture (so the same seed gives the same
mechanics on every texture, and gains are comparable across textures).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from evaluation.realgel.elastic import ContactPatch, PressureBasis
from evaluation.realgel.textures import SIZE_HW, TEXTURES, load_texture, split_illumination

TILT_RATIO = 0.5
INVERSE_ITERATIONS = 4
CONTACTS = ("centred", "varied")


@dataclass(frozen=True)
class SequenceSpec:
    """One slip-free tilt sequence.

    ``axis``: the tilt axis, x or y (frame S). ``push``: relative swing of the grip pressure
    (0: none). ``tilt_px``: peak of the tilt's displacement at full tilt, px at 320 x 240.
    ``noise_grey``: camera noise sigma, grey levels. ``frames``: frames after the reference.
    ``lighting``: amplitude of a lighting drift (``lighting_drift``), relative; 0: steady.
    ``shading``: whether the capture's LED shading moves with the gel or stays (module
    docstring). ``contact``: "centred" (a near-centred contact of moderate aspect) or
    "varied" (any aspect from tall to flat, anywhere in the middle of the gel;
    ``random_patch``).
    """

    texture: str
    axis: Literal["x", "y"]
    push: float
    tilt_px: float
    noise_grey: float
    seed: int
    frames: int = 160
    lighting: float = 0.0
    shading: Literal["moves", "fixed"] = "moves"
    contact: Literal["centred", "varied"] = "centred"

    def __post_init__(self) -> None:
        if self.texture not in TEXTURES:
            raise ValueError(
                f"unknown texture {self.texture!r}; expected one of {', '.join(TEXTURES)}"
            )
        if self.axis not in ("x", "y"):
            raise ValueError(f"tilt axis must be 'x' or 'y', got {self.axis!r}")
        if not 0.0 <= self.push <= 1.0 - TILT_RATIO:
            raise ValueError(f"push must be in [0, {1.0 - TILT_RATIO}], got {self.push}")
        if self.shading not in ("moves", "fixed"):
            raise ValueError(f"shading must be 'moves' or 'fixed', got {self.shading!r}")
        if self.contact not in CONTACTS:
            raise ValueError(f"contact must be one of {', '.join(CONTACTS)}, got {self.contact!r}")
        if not 0.0 <= self.lighting < 1.0:
            raise ValueError(f"lighting drift must be in [0, 1), got {self.lighting}")
        if self.frames < 4:
            raise ValueError(f"a sequence needs at least 4 frames, got {self.frames}")

    @property
    def label(self) -> str:
        push = f", push ±{self.push:.0%}" if self.push else ""
        lighting = f", light ±{self.lighting:.0%}" if self.lighting else ""
        shading = ", fixed shading" if self.shading == "fixed" else ""
        contact = ", varied contact" if self.contact == "varied" else ""
        return f"tilt {self.axis}{push}{lighting}{shading}{contact}"


def random_patch(
    rng: np.random.Generator, height: int, width: int, contact: str = "centred"
) -> ContactPatch:
    """With ``contact`` "centred": a contact covering 35-65% of the width and 45-80% of the
    height, its centre within 8% of the image centre. "varied": the face of a grasped plug in
    any pose, an aspect (width / height) log-uniform in [1/4, 4] and 6-30% of the image's
    area, its centre up to 20% of the image's size from the image centre, and at least 4% of
    the image's size from every border."""
    if contact == "varied":
        aspect = float(np.exp(rng.uniform(np.log(0.25), np.log(4.0))))
        area = rng.uniform(0.06, 0.30) * height * width
        half_w = min(0.5 * np.sqrt(area * aspect), 0.46 * width)
        half_h = min(0.5 * np.sqrt(area / aspect), 0.46 * height)
        room_x = min(0.2 * width, 0.46 * width - half_w)
        room_y = min(0.2 * height, 0.46 * height - half_h)
        return ContactPatch(
            cx=width / 2 + rng.uniform(-room_x, room_x),
            cy=height / 2 + rng.uniform(-room_y, room_y),
            half_w=float(half_w),
            half_h=float(half_h),
        )
    return ContactPatch(
        cx=width / 2 + rng.uniform(-0.08, 0.08) * width,
        cy=height / 2 + rng.uniform(-0.08, 0.08) * height,
        half_w=rng.uniform(0.175, 0.325) * width,
        half_h=rng.uniform(0.225, 0.4) * height,
    )


def signals(rng: np.random.Generator, frames: int, push: float) -> tuple[np.ndarray, np.ndarray]:
    """(tilt, grip) per frame: the tilt in [-1, 1] (two incommensurate sines, scaled to peak
    at 1), and the grip pressure relative to the grasp, 1 +- ``push`` (a third sine)."""
    t = np.arange(frames) / frames
    phases = rng.uniform(0.0, 2.0 * np.pi, 3)
    tilt = 0.7 * np.sin(2 * np.pi * 2.5 * t + phases[0]) + 0.3 * np.sin(
        2 * np.pi * 5.3 * t + phases[1]
    )
    tilt /= np.abs(tilt).max()
    grip = 1.0 + push * np.sin(2 * np.pi * 1.7 * t + phases[2])
    return tilt, grip


def lighting_drift(
    rng: np.random.Generator, frames: int, height: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """A drifting LED light, as (ramps (H, W, 3), swings (frames, 3)): frame i's gain in
    channel c is ``1 + amplitude * swings[i, c] * ramps[..., c]``. Each channel swings on
    its own slow sine (random phase), more on one side of the image than the other (a linear
    ramp from 0.5 to 1 in a random direction per channel, as LEDs on different sides)."""
    y, x = np.mgrid[0:height, 0:width]
    t = np.arange(frames) / frames
    ramps = np.empty((height, width, 3), np.float32)
    swings = np.empty((frames, 3))
    for channel in range(3):
        angle = rng.uniform(0.0, 2.0 * np.pi)
        ramp = np.cos(angle) * (x / width - 0.5) + np.sin(angle) * (y / height - 0.5)
        ramps[..., channel] = 0.5 + 0.5 * (ramp - ramp.min()) / np.ptp(ramp)
        swings[:, channel] = np.sin(2 * np.pi * 1.3 * t + rng.uniform(0.0, 2.0 * np.pi))
    return ramps, swings


def inverse_map(field_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For a forward field u (H, W, 2) taking gel point X to X + u(X), the maps (map_x,
    map_y) float32 giving, at each image pixel x, the gel point X with X + u(X) = x."""
    height, width = field_px.shape[:2]
    grid_y, grid_x = np.mgrid[0:height, 0:width].astype(np.float32)
    u = np.ascontiguousarray(field_px[..., 0], np.float32)
    v = np.ascontiguousarray(field_px[..., 1], np.float32)
    map_x, map_y = grid_x - u, grid_y - v
    for _ in range(INVERSE_ITERATIONS):
        u_at = cv2.remap(u, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        v_at = cv2.remap(v, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        map_x, map_y = grid_x - u_at, grid_y - v_at
    return map_x, map_y


def warp(texture: np.ndarray, field_px: np.ndarray) -> np.ndarray:
    """The float texture with its gel points moved by the forward field (H, W, 2), px."""
    map_x, map_y = inverse_map(field_px)
    return cv2.remap(texture, map_x, map_y, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT_101)


def add_noise(image: np.ndarray, sigma: float, rng: np.random.Generator) -> np.ndarray:
    noisy = image + rng.normal(0.0, sigma, image.shape).astype(np.float32)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)


@dataclass(frozen=True)
class Mechanics:
    """The deformation of a sequence: the field of each frame is ``field(i)`` (H, W, 2) px;
    ``truth`` (frames, 2) the applied tilt torque (tau_x, tau_y) per frame, arbitrary units
    (px^3 times pressure); ``tilt`` and ``grip`` the signals; ``tilt_weight`` the tilt's
    pressure map's weight (1, or below 1 for a tilt across a varied contact's shorter side,
    ``mechanics``)."""

    basis: PressureBasis
    scale: float
    grip_weight: float
    tilt_index: int
    tilt_weight: float
    tilt: np.ndarray
    grip: np.ndarray
    truth: np.ndarray

    def field(self, tilt: float, grip: float) -> np.ndarray:
        fields = self.basis.fields
        return self.scale * (
            grip * self.grip_weight * fields[0]
            + tilt * self.tilt_weight * fields[1 + self.tilt_index]
        )

    def relative_field(self, index: int) -> np.ndarray:
        """The true displacement (H, W, 2) px of frame ``index`` against the reference, at
        each pixel of the reference image (the gel point seen there in the reference)."""
        reference = self.field(0.0, 1.0)
        change = self.field(self.tilt[index], self.grip[index]) - reference
        map_x, map_y = inverse_map(reference)
        return cv2.remap(
            change.astype(np.float32),
            map_x,
            map_y,
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )

    def tilt_field(self) -> np.ndarray:
        """The tilt's own part of the field at full tilt (peaks at tilt_px)."""
        return self.scale * self.tilt_weight * self.basis.fields[1 + self.tilt_index]


def mechanics(spec: SequenceSpec) -> Mechanics:
    """The contact, signals and truth of ``spec`` (independent of its texture and noise).

    On the "centred" contact the tilt's own field peaks at ``tilt_px`` whatever the axis. On
    a "varied" contact the object's face tilts by the same angle about either axis: the
    pressure's slope per px is the same, so the edge pressures change by ``TILT_RATIO`` of
    the grip across the contact's longer side and proportionally less across its shorter
    side, and ``tilt_px`` is the peak of the field of a full tilt across the longer side: a
    tilt across a narrow contact moves the gel less for the same angle."""
    rng = np.random.default_rng([spec.seed, 0])
    height, width = SIZE_HW
    patch = random_patch(rng, height, width, spec.contact)
    basis = PressureBasis.for_patch(patch, height, width)
    tilt, grip = signals(rng, spec.frames, spec.push)
    index = 0 if spec.axis == "x" else 1
    weight, widest = 1.0, index
    if spec.contact == "varied":  # half sizes across which tilt x and tilt y vary
        across = (patch.half_h, patch.half_w)
        widest = int(np.argmax(across))
        weight = across[index] / across[widest]
    peak = float(np.hypot(*np.moveaxis(basis.fields[1 + widest], -1, 0)).max())
    scale = spec.tilt_px / peak
    truth = tilt[:, None] * basis.tilt_moments[index][None, :] * (scale * weight)
    return Mechanics(basis, scale, 1.0 / TILT_RATIO, index, weight, tilt, grip, truth)


@dataclass(frozen=True)
class RenderedSequence:
    """A sequence's images: ``open_frames`` (the noisy capture unwarped: the gel before the
    grasp), ``references`` (noisy grasp frames without tilt, for zeroing) and ``frames``
    (uint8 BGR, 240 x 320), with its ``spec`` and ``mechanics``."""

    spec: SequenceSpec
    mechanics: Mechanics
    open_frames: list[np.ndarray]
    references: list[np.ndarray]
    frames: list[np.ndarray]


def render(spec: SequenceSpec, reference_frames: int = 1) -> RenderedSequence:
    """Render ``spec``'s frames, ``reference_frames`` noisy references and as many open
    frames. The noise is seeded by the spec's seed and texture (the open frames' on a stream
    of their own, so the other frames are those rendered before open frames existed)."""
    texture = load_texture(spec.texture)
    illumination = np.float32(1.0)
    if spec.shading == "fixed":
        illumination, texture = split_illumination(texture)
    mech = mechanics(spec)
    rng = np.random.default_rng([spec.seed, 1, sorted(TEXTURES).index(spec.texture)])
    reference = illumination * warp(texture, mech.field(0.0, 1.0))
    references = [add_noise(reference, spec.noise_grey, rng) for _ in range(reference_frames)]
    open_rng = np.random.default_rng([spec.seed, 4, sorted(TEXTURES).index(spec.texture)])
    open_image = illumination * texture
    open_frames = [
        add_noise(open_image, spec.noise_grey, open_rng) for _ in range(reference_frames)
    ]
    ramps, swings = lighting_drift(np.random.default_rng([spec.seed, 3]), spec.frames, *SIZE_HW)
    frames = []
    for tilt, grip, swing in zip(mech.tilt, mech.grip, swings, strict=True):
        image = illumination * warp(texture, mech.field(tilt, grip))
        if spec.lighting:
            image *= 1.0 + spec.lighting * (swing * ramps)
        frames.append(add_noise(image, spec.noise_grey, rng))
    return RenderedSequence(spec, mech, open_frames, references, frames)
