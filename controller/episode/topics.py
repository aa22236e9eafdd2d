"""Every topic of an episode file: its name, schema, encoding, frame and units.

This table is the episode format's contract (docs/EPISODES.md): the writer
(``controller.episode.writer``) writes these ``Topic`` objects, with these schemas, and the
reader (``controller.episode.reader``) decodes by the schemas the file carries. Times: every
message's MCAP ``log_time`` is the **wall clock** of the recording in integer nanoseconds
since the Unix epoch: the loop's time (``t_s``; in simulation the world's clock, on the
robot ``time.monotonic``) plus the offset fixed when the file is created (wall clock minus
loop clock then; metadata ``log_time_offset_ns``), so a viewer shows when the run happened.
A JSON message's own ``t_s``/``start_s`` fields stay on the loop's clock; the Foxglove
messages' ``timestamp`` (a frame's capture, a transform's time) is on the log-time clock, so
a viewer lines them up with the log times; the reader gives both back on the loop's clock.
Frames (docs/ARCHITECTURE.md): ``B`` the arm base, ``T`` the tool (TCP), ``S`` the tactile
sensor (placed in T by ``/tf_static``), ``H`` the hole. SI units unless a field's name says
otherwise; the raw tactile estimate's units are the estimator's (mm, mm^2) unless
``calibrated``.

Two encodings (an absent field reads as None: ``controller.episode.reader``):

* ``protobuf``: Foxglove's well-known schemas (``foxglove.CompressedImage``,
  ``foxglove.Grid``, ``foxglove.FrameTransforms``), encoded by ``foxglove-sdk``'s message
  classes, so Foxglove's image, plot and 3D panels show them without a converter;
* ``json``: our messages, one JSON object each, with a JSON Schema (``jsonschema``)
  registered in the file, named ``tactile_insertion.NAME``. Every field has one JSON type
  (no ``anyOf``, no ``null``, a ``type`` beside every ``enum``): the rules of Foxglove's
  JSON-schema parser (Foxglove Studio's and Lichtblick's ``parseJsonSchema``), which drops a
  channel whose schema has a field of any other form. A value that is absent (a number that
  is not finite, a vector or a fault the tick has none of) is an absent key, never null;
  the reader gives every field of the schema that a message lacks back as None (as files
  of format 1 wrote null).

Rates (each ``Topic.rate``): most topics have a message per tick or per frame. The
**latched** topics (``/gripper/status``, ``/teleop/input``: values that change seldom) have
one at the first tick, at each tick whose value changed, and at the first tick 1 s or more
of loop time after the last one written (``controller.episode.recorder.LATCH_PERIOD_S``): a
tick without a message holds the value of the newest message at or before it, which is at
most 1 s and one tick older.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from controller.tactile.wrench import FLAG_FIELDS, VALUE_FIELDS

FORMAT_VERSION = "2"
"""The episode format's version (metadata ``episode.format_version``). 2: log times on the
wall clock (``log_time_offset_ns``), JSON schemas of one type per field (an absent value an
absent key), ``/tf_static``. The reader reads 1 and 2 and refuses any other."""

READABLE_VERSIONS = ("1", "2")
"""The major versions the reader reads."""

PROFILE = "tactile-insertion"
"""The MCAP header's profile string."""

Encoding = Literal["protobuf", "json"]


@dataclass(frozen=True)
class Topic:
    """One stream: ``name`` (the MCAP topic), ``schema`` (the schema's name), ``encoding``
    (the message encoding), ``frame`` (the frame its values are expressed in, "" for none),
    ``rate`` (when a message is written) and ``doc`` (fields and units)."""

    name: str
    schema: str
    encoding: Encoding
    frame: str
    rate: str
    doc: str


def _json_schema(properties: Mapping[str, Any], required: tuple[str, ...] = ()) -> dict:
    return {"type": "object", "properties": dict(properties), "required": list(required)}


_NUM = {"type": "number"}
_BOOL = {"type": "boolean"}
_STR = {"type": "string"}
_INT = {"type": "integer"}
_VEC3 = {"type": "array", "items": _NUM, "minItems": 3, "maxItems": 3}
_NUMS = {"type": "array", "items": _NUM}
_STRS = {"type": "array", "items": _STR}


def _enum(*values: str) -> dict:
    return {"type": "string", "enum": list(values)}


TACTILE_IMAGE = Topic(
    "/tactile/image",
    "foxglove.CompressedImage",
    "protobuf",
    "S",
    "every frame pushed into the estimator (the camera's own rate)",
    "The frame as the estimator received it. ``timestamp``: the frame's capture time on the "
    "loop's clock; ``log_time``: when it was pushed; ``format``: 'jpeg' (default, lossy) or "
    "'png' (lossless: re-estimation reproduces the logged estimates exactly); ``frame_id`` "
    "'S'. Image rows down (S's y), columns right (S's x); colour order as any JPEG/PNG "
    "(decoded by OpenCV: BGR, as the estimator takes it).",
)
TACTILE_FIELD = Topic(
    "/tactile/field",
    "foxglove.Grid",
    "protobuf",
    "S",
    "each frame pushed once the estimator has a reference",
    "The estimator's displacement field on its grid, row-major, row 0 at the smallest y "
    "(image top): three float32 fields per cell, ``u_mm`` and ``v_mm`` (displacement along "
    "S's x and y, mm) and ``div`` (du/dx + dv/dy, dimensionless). ``cell_size`` is in m, "
    "``pose`` places the grid's corner (cell (0, 0)'s outer corner) in S, ``frame_id`` 'S'. "
    "``timestamp``: the frame's capture time.",
)
TACTILE_WRENCH = Topic(
    "/tactile/wrench",
    "tactile_insertion.WrenchEstimate",
    "json",
    "S",
    "each frame pushed (one estimate per frame)",
    "The estimate the controller saw (``controller.tactile.WrenchEstimate``, after any "
    "``TransformedSource``): ``t_s`` (the frame's capture time), tau_x, tau_y, tau_z, "
    "shear_x, shear_y, normal and the FingerVision baseline's fv_tau_x/y/z (raw: mm, tau_z "
    "and fv mm^2; N*m / N when ``calibrated``; a non-finite value is absent), the flags "
    "(contact, degenerate, slip_suspected, slip_gross, rezero_recommended, zeroing, "
    "calibrated) and ``push_index``: the frame's index among the pushes (0-based; the image "
    "of the same push has the same index in ``/tactile/push``).",
)
TACTILE_PUSH = Topic(
    "/tactile/push",
    "tactile_insertion.SourceCall",
    "json",
    "",
    "each call into the wrench source, in the order made",
    "The calls the loop made into the wrench source, so a re-estimation repeats them in the "
    "same order: ``call`` 'push' (``push_index``, ``frame_t_s``: capture time, s), "
    "'capture_open' or 'rezero' (``n_frames``: the frames asked for, absent for the "
    "source's default; ``push_index``: the index of the next push, which is the first frame "
    "the call affects). Messages of one file are ordered by log_time, and those of equal "
    "log_time by their order in the file.",
)
COMMAND = Topic(
    "/control/command",
    "tactile_insertion.Command",
    "json",
    "B",
    "every tick",
    "The command as sent, after the limits: ``twist_linear_m_s`` and ``twist_angular_rad_s`` "
    "(TCP twist in B) or absent, ``pose_xyz_m`` and ``pose_rpy_rad`` (servo target, T2B) "
    "or absent, ``gripper_width_m``, ``gripper_speed_m_s``, ``gripper_force_n`` (a new gripper "
    "target) or absent, ``capture_open_tactile``, ``rezero_tactile``, ``limited`` (the limits "
    "that changed it, e.g. 'speed', 'workspace', 'tilt'), ``rule`` (the machine's rule that "
    "decided it, 'phase.rule', e.g. 'search.drag', 'align.torque_servo'; '' when the machine "
    "names none), ``stage`` (the sub-stage in which the rule was decided, 'phase.stage', e.g. "
    "'align.seek'; '' when the machine has none), ``sent`` (false on a fault tick: nothing "
    "was sent) and ``fault`` (the watchdog's trip message; absent without one).",
)
ARM_STATUS = Topic(
    "/arm/status",
    "tactile_insertion.ArmStatus",
    "json",
    "B",
    "every tick (the status the machine saw)",
    "``t_s`` (read time), ``tcp_xyz_m``, ``tcp_rpy_rad`` (T2B, xArm rpy), ``joints_rad`` (6; "
    "absent when any is unknown, e.g. the simulated arm), ``mode``, ``state``, ``error_code``, "
    "``warning_code``, ``external_force_n`` (N, B: the F/T sensor's force on the tool; "
    "absent without one).",
)
GRIPPER_STATUS = Topic(
    "/gripper/status",
    "tactile_insertion.GripperStatus",
    "json",
    "",
    "latched: the first tick, each tick whose status differs from the last one written in "
    "any field but ``t_s``, and the first tick 1 s or more after the last one written; a "
    "tick without one holds the previous value",
    "``t_s``, ``activated``, ``moving``, ``object`` (the Hand-E's object detection), "
    "``width_m`` (finger opening), ``fault_code``, ``fault_message``.",
)
TELEOP = Topic(
    "/teleop/input",
    "tactile_insertion.TeleopInput",
    "json",
    "B",
    "latched: the first tick, each tick whose input differs from the last one written, and "
    "the first tick 1 s or more after the last one written; a tick without one holds the "
    "previous value",
    "The gamepad after arbitration (``controller.teleop``): ``connected``, ``in_control`` "
    "(true: the operator drives the arm; false: the machine), ``in_control_by`` ('operator' "
    "or 'machine'), ``twist_linear_m_s``, ``twist_angular_rad_s`` (the operator's TCP twist "
    "in B), ``gripper_open``, ``gripper_close``, ``hand_back``, ``estop``, ``estop_ack``, "
    "``deadman`` (the deadman button held).",
)
TRANSITION = Topic(
    "/machine/transition",
    "tactile_insertion.Transition",
    "json",
    "",
    "each phase change (the file is flushed at once)",
    "``t_s``, ``from``, ``to`` (phases, controller.insertion.Phase values), ``reason`` (the "
    "guard: e.g. 'hole_found', or a FailureReason's value) and ``rule`` (which of the "
    "guard's rules fired, e.g. 'torque_catch', 'load_drop'; '' when it has one).",
)
GRASP_ESTIMATE = Topic(
    "/machine/grasp_estimate",
    "tactile_insertion.GraspEstimate",
    "json",
    "T",
    "each estimate of the plug in the hand the machine makes (FEEL's; none in a run without)",
    "``t_s`` (when it was made), ``plane`` ('thickness': the tilt about T x, the tip moved "
    "along T y; 'width': about T y, along T x), ``tilt_rad`` (the TCP turn that sets the plug "
    "upright in that plane), ``tip_offset_m`` (the tip's offset from the nominal it implies, "
    "m), ``method`` ('rock': the pressed tip rocked until its face lies flat; 'imprint': the "
    "grasp's contact centre, a tip along T x and no tilt, ``tilt_rad`` absent) and ``kept`` "
    "(it passed its checks: the machine acts on it; controller.insertion.InHandEstimate).",
)
LOOP_TICK = Topic(
    "/loop/tick",
    "tactile_insertion.LoopTick",
    "json",
    "",
    "every tick",
    "``index``, ``deadline_s``, ``start_s``, ``end_s`` (s on the loop's clock), ``overran``, "
    "``phase`` (the machine's phase after its step) and ``fault`` (the trip; absent without one).",
)
TCP_TF = Topic(
    "/tf",
    "foxglove.FrameTransforms",
    "protobuf",
    "B",
    "every 4th tick (25 Hz: controller/episode/recorder.py, TF_PERIOD_S)",
    "The TCP pose: parent 'B', child 'T', translation in m, rotation a unit quaternion "
    "(from the xArm rpy, core.spatial's 'xyz' convention). ``/tf_static`` places S in T; in "
    "simulation the truth adds, on ``/sim/tf``, the plug ('plug', S2B) and the hole ('H').",
)
TF_STATIC = Topic(
    "/tf_static",
    "foxglove.FrameTransforms",
    "protobuf",
    "T",
    "latched: the first tick, then again at the first tick 1 s or more after the last one "
    "written (it never changes; repeated so a viewer that seeks or joins late has it)",
    "Where the sensor sits on the tool: parent 'T', child 'S' (S2T: the rotation of the "
    "machine's ``signals.torque_axes``, the origin at the gel's centre, half the plug's "
    "thickness along +y_T), so the 3D panel places the tactile field's grid (frame S) on "
    "the tool.",
)
DROPS = Topic(
    "/episode/drops",
    "tactile_insertion.Drops",
    "json",
    "",
    "when the queue overflowed, at most every flush",
    "Records the writer dropped (its queue was full, or it could not encode the payload): "
    "``dropped_total`` (since the start) and ``by_topic`` (topic -> count since the start).",
)
SIM_TRUTH = Topic(
    "/sim/truth",
    "tactile_insertion.SimTruth",
    "json",
    "",
    "each row of the scene's truth (simulation only; never fed to the controller)",
    "drivers/sim/scenes/insertion/truth.py's row: ``t_s``, ``gel_wrench_s`` (fx, fy, fz N; "
    "tau_x, tau_y, tau_z N*m: the gel on the plug, in S), ``wrist_wrench_t`` (6, N and N*m), "
    "``tip_xyz_b`` (m, B), ``plug_quat_b`` (w, x, y, z; S2B), ``depth_m`` (tip below the "
    "board surface), ``contact_force_n`` (summed normal, N), ``insertion_force_n`` (along the "
    "hole's axis, N).",
)
SIM_TF = Topic(
    "/sim/tf",
    "foxglove.FrameTransforms",
    "protobuf",
    "B",
    "every 4th truth row (25 Hz, as ``/tf``; simulation only)",
    "The plug's true pose ('B' -> 'plug': origin at its tip, rotation S2B) and the true hole "
    "('B' -> 'H', with each row, so a viewer joining late still sees it).",
)

TOPICS: Mapping[str, Topic] = {
    t.name: t
    for t in (
        TACTILE_IMAGE,
        TACTILE_FIELD,
        TACTILE_WRENCH,
        TACTILE_PUSH,
        COMMAND,
        ARM_STATUS,
        GRIPPER_STATUS,
        TELEOP,
        TRANSITION,
        GRASP_ESTIMATE,
        LOOP_TICK,
        TCP_TF,
        TF_STATIC,
        DROPS,
        SIM_TRUTH,
        SIM_TF,
    )
}
"""Every topic by name."""

JSON_SCHEMAS: Mapping[str, dict] = {
    TACTILE_WRENCH.schema: _json_schema(
        {
            "t_s": _NUM,
            "push_index": _INT,
            **{k: _NUM for k in VALUE_FIELDS},
            **{k: _BOOL for k in FLAG_FIELDS},
        },
        ("t_s", "push_index"),
    ),  # fmt: skip
    TACTILE_PUSH.schema: _json_schema(
        {
            "call": _enum("push", "capture_open", "rezero"),
            "push_index": _INT,
            "frame_t_s": _NUM,
            "n_frames": _INT,
        },
        ("call", "push_index"),
    ),
    COMMAND.schema: _json_schema(
        {
            "twist_linear_m_s": _VEC3,
            "twist_angular_rad_s": _VEC3,
            "pose_xyz_m": _VEC3,
            "pose_rpy_rad": _VEC3,
            "gripper_width_m": _NUM,
            "gripper_speed_m_s": _NUM,
            "gripper_force_n": _NUM,
            "capture_open_tactile": _BOOL,
            "rezero_tactile": _BOOL,
            "limited": _STRS,
            "rule": _STR,
            "stage": _STR,
            "sent": _BOOL,
            "fault": _STR,
        },
        ("sent", "limited"),
    ),
    ARM_STATUS.schema: _json_schema(
        {
            "t_s": _NUM,
            "tcp_xyz_m": _VEC3,
            "tcp_rpy_rad": _VEC3,
            "joints_rad": _NUMS,
            "mode": _STR,
            "state": _STR,
            "error_code": _INT,
            "warning_code": _INT,
            "external_force_n": _VEC3,
        },
        ("t_s", "tcp_xyz_m", "tcp_rpy_rad"),
    ),
    GRIPPER_STATUS.schema: _json_schema(
        {
            "t_s": _NUM,
            "activated": _BOOL,
            "moving": _BOOL,
            "object": _STR,
            "width_m": _NUM,
            "fault_code": _INT,
            "fault_message": _STR,
        },
        ("t_s", "width_m"),
    ),
    TELEOP.schema: _json_schema(
        {
            "connected": _BOOL,
            "in_control": _BOOL,
            "in_control_by": _enum("operator", "machine"),
            "twist_linear_m_s": _VEC3,
            "twist_angular_rad_s": _VEC3,
            **{
                k: _BOOL
                for k in (
                    "gripper_open",
                    "gripper_close",
                    "hand_back",
                    "estop",
                    "estop_ack",
                    "deadman",
                )  # fmt: skip
            },
        },
        ("in_control", "in_control_by"),
    ),
    TRANSITION.schema: _json_schema(
        {"t_s": _NUM, "from": _STR, "to": _STR, "reason": _STR, "rule": _STR},
        ("t_s", "from", "to", "reason"),
    ),
    GRASP_ESTIMATE.schema: _json_schema(
        {
            "t_s": _NUM,
            "plane": _enum("thickness", "width"),
            "tilt_rad": _NUM,
            "tip_offset_m": _NUM,
            "method": _STR,
            "kept": _BOOL,
        },
        ("t_s", "plane", "method", "kept"),
    ),
    LOOP_TICK.schema: _json_schema(
        {
            "index": _INT,
            "deadline_s": _NUM,
            "start_s": _NUM,
            "end_s": _NUM,
            "overran": _BOOL,
            "phase": _STR,
            "fault": _STR,
        },
        ("index", "start_s", "phase"),
    ),
    DROPS.schema: _json_schema(
        {
            "dropped_total": _INT,
            "by_topic": {"type": "object", "properties": {name: _INT for name in TOPICS}},
        },
        ("dropped_total", "by_topic"),
    ),
    SIM_TRUTH.schema: _json_schema(
        {
            "t_s": _NUM,
            "gel_wrench_s": _NUMS,
            "wrist_wrench_t": _NUMS,
            "tip_xyz_b": _NUMS,
            "plug_quat_b": _NUMS,
            "depth_m": _NUM,
            "contact_force_n": _NUM,
            "insertion_force_n": _NUM,
        },
        ("t_s",),
    ),
}
"""The JSON Schema of each ``json`` topic's schema name."""

METADATA_EPISODE = "episode"
"""The metadata record written at the start: ``format_version``, ``log_time_offset_ns``
(integer ns since the Unix epoch: a message's log time minus it is the loop's time; written
by the writer), ``task``, ``task_file``,
``overrides`` (JSON list), ``seed``, ``controller``, ``backend``, ``package_version``,
``git_revision`` (or "unknown"), ``machine`` (host, CPU, OS, Python), ``started_utc`` (ISO
8601 wall clock), ``tactile_image_format`` ('jpeg' or 'png'), ``jpeg_quality``,
``queue_size``, ``flush_interval_s``."""

METADATA_OUTCOME = "outcome"
"""The metadata record written at the end (absent if the process was killed): ``reason``,
``message``, ``phase`` (the loop's end), ``dropped_total``, ``dropped_by_topic`` (JSON),
``result`` (JSON: the trial's result row where a trial tool ran it), ``error`` (an
exception that ended the run, else "")."""

METADATA_REPAIR = "repair"
"""Written by ``repair``: ``complete`` "false", ``source_bytes`` (the source file's size),
``read_bytes`` (where its readable records end), ``messages`` (recovered), ``lost_bytes``
and ``lost_ranges`` (the damaged byte ranges skipped, ``START..END`` separated by spaces)."""

ATTACHMENT_MEDIA_TYPE = "application/yaml"
"""The media type of every attachment (both are YAML)."""

ATTACHMENT_TASK = "task.yaml"
"""The attachment holding the resolved task configuration (the merged, overridden task file
as YAML; ``ATTACHMENT_MEDIA_TYPE``)."""
ATTACHMENT_CALIBRATION = "calibration.yaml"
"""The attachment holding the calibration the run applied to the estimates (the task's
``calibration:`` file's content, controller/tactile/calibration.py's format; absent when the
run's estimates were raw), so a re-estimation can apply it again."""
