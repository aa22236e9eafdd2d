"""Real-texture recordings: the press-tilt-release program rendered on a real gel capture,
written as a video with its true program beside it.

    render_recording("gelsight_markers_a", OUT_DIR) -> (OUT_DIR/gelsight_markers_a.mkv,
                                                       OUT_DIR/gelsight_markers_a.csv)

The gel model (drivers/sim/gel) holds a ``plate`` under the program of
drivers/sim/scenes/press_tilt.py; each frame is the capture (``real:<capture>``,
drivers/sim/render/real_texture.py) warped by the model's field, with the evaluation's
nominal camera noise (evaluation/common/rendering.py), at the capture's sensor's working size
(``digit_*`` captures: the DIGIT, the others: the GelSight Mini), with the sensor's tilt
torque ``TILT_NM``.

The video is FFV1 in Matroska (lossless; OpenCV's FFmpeg backend writes and reads it) at the
program's rate. The CSV has one row per frame: ``frame,time_s,phase,segment,grip_n,tau_x_nm,
tau_y_nm,contact``: the program's grip and the tilt torques the gel model actually carried
(N*m, frame S, the wrench the gel exerts on the object), ``contact`` 1 when the object
touches the gel.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from controller.cli.outputs import atomic_text
from drivers.sim.render.real_texture import real_gel_names
from drivers.sim.scenes.press_tilt import PressTiltConfig, press_tilt_program, press_tilt_states
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_model

VIDEO_FOURCC = "FFV1"
VIDEO_SUFFIX = ".mkv"
OBJECT = "plate"
TILT_NM = {"gelsight_mini": 0.012, "digit": 0.024}
"""Peak tilt torque per sensor, N*m: on the plate at the 10 N grip, the tilt's own motion
peaks at about 0.5 px at 320 x 240 on both gels (the DIGIT's domed gel is stiffer)."""
TRUTH_COLUMNS = ("frame", "time_s", "phase", "segment", "grip_n", "tau_x_nm", "tau_y_nm", "contact")


def capture_sensor(capture: str) -> str:
    """The sensor whose working image a capture is rendered at; ValueError for an unknown
    capture (naming the known ones)."""
    if capture not in real_gel_names():
        raise ValueError(f"capture '{capture}': expected one of {', '.join(real_gel_names())}")
    return "digit" if capture.startswith("digit") else "gelsight_mini"


@dataclass(frozen=True)
class Truth:
    """A recording's true program, read back from its CSV: per frame the segment name,
    the carried tilt torques (N, 2) N*m and whether the object touches the gel."""

    segments: tuple[str, ...]
    tau_nm: np.ndarray
    contact: np.ndarray


def write_video(path: Path, frames: list[np.ndarray], rate_hz: float) -> None:
    """Write uint8 BGR ``frames`` (all one size) losslessly to ``path`` (.mkv)."""
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(
        str(path), cv2.VideoWriter_fourcc(*VIDEO_FOURCC), rate_hz, (width, height)
    )
    if not writer.isOpened():
        raise OSError(f"'{path}': OpenCV cannot write {VIDEO_FOURCC} video here")
    try:
        for frame in frames:
            writer.write(frame)
    finally:
        writer.release()


def recording_program(capture: str, config: PressTiltConfig | None = None) -> PressTiltConfig:
    """``config`` (None: the defaults with the sensor's ``TILT_NM``) for ``capture``."""
    return config or PressTiltConfig(tilt_nm=TILT_NM[capture_sensor(capture)])


def render_recording(
    capture: str, out_dir: Path, config: PressTiltConfig | None = None, seed: int = 0
) -> tuple[Path, Path]:
    """Render the program (``recording_program``) on ``capture`` and write
    ``out_dir/<capture>.mkv`` and its truth ``out_dir/<capture>.csv``; returns both paths."""
    sensor = capture_sensor(capture)
    config = recording_program(capture, config)
    program = press_tilt_program(config)
    states = press_tilt_states(gel_model(sensor, OBJECT), program)
    renderer = make_renderer(sensor, seed=seed, appearance=f"real:{capture}")
    frames = [renderer.render(s.field_px, frame_index=i) for i, s in enumerate(states)]
    out_dir.mkdir(parents=True, exist_ok=True)
    video, truth = out_dir / f"{capture}{VIDEO_SUFFIX}", out_dir / f"{capture}.csv"
    write_video(video, frames, config.rate_hz)
    with atomic_text(truth, newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(TRUTH_COLUMNS)
        for i, (step, state) in enumerate(zip(program, states, strict=True)):
            writer.writerow(
                [
                    i,
                    f"{step.t_s:.6f}",
                    step.phase,
                    step.segment,
                    f"{step.grip_n:.6g}",
                    f"{state.carried.tau_x:.9g}",
                    f"{state.carried.tau_y:.9g}",
                    int(state.in_contact.any()),
                ]
            )
    return video, truth


def read_truth(path: Path) -> Truth:
    """The truth CSV written by ``render_recording``."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    return Truth(
        segments=tuple(row["segment"] for row in rows),
        tau_nm=np.array([[float(row["tau_x_nm"]), float(row["tau_y_nm"])] for row in rows]),
        contact=np.array([row["contact"] == "1" for row in rows]),
    )
