"""Find a camera's capture node by its persistent name in ``/dev/v4l/by-id``.

udev names each V4L2 node of a USB camera ``usb-<vendor>_<model>_<serial>-video-index<N>``.
A UVC camera has two nodes: ``-index0`` captures video, ``-index1`` carries UVC metadata and
cannot stream images. We match the configured pattern (``fnmatch``, case-sensitive) against
the entries, keep the ``-index0`` ones and resolve the link to ``/dev/videoN``.
"""

from __future__ import annotations

import fnmatch
import os

from core.errors import DeviceNotConnectedError

CAPTURE_SUFFIX = "-index0"


def find_capture_node(device: str, pattern: str, by_id_dir: str = "/dev/v4l/by-id") -> str:
    """The resolved path (``/dev/videoN``) of the one ``-index0`` entry of ``by_id_dir`` whose
    name matches ``pattern``.

    Raises DeviceNotConnectedError (naming ``device``) when the directory is missing, nothing
    or more than one capture node matches (the message lists what was found), or the link
    points nowhere.
    """
    if not os.path.isdir(by_id_dir):
        raise DeviceNotConnectedError(
            device,
            f"{by_id_dir} does not exist: no USB camera is plugged in (or udev is not running)",
        )
    entries = sorted(os.listdir(by_id_dir))
    matches = [e for e in entries if fnmatch.fnmatchcase(e, pattern) and e.endswith(CAPTURE_SUFFIX)]
    if not matches:
        found = ", ".join(entries) if entries else "nothing"
        raise DeviceNotConnectedError(
            device,
            f"no capture node ('{CAPTURE_SUFFIX}') in {by_id_dir} matches {pattern!r}; "
            f"found: {found}. Check the cable, or fix by_id_pattern.",
        )
    if len(matches) > 1:
        raise DeviceNotConnectedError(
            device,
            f"{pattern!r} matches {len(matches)} capture nodes in {by_id_dir}: "
            f"{', '.join(matches)}. Put the serial number in by_id_pattern.",
        )
    link = os.path.join(by_id_dir, matches[0])
    node = os.path.realpath(link)
    if not os.path.exists(node):
        raise DeviceNotConnectedError(device, f"{link} points to {node}, which does not exist")
    return node
