"""The Foxglove layout in docs/ names only topics the episode has, and every message path of
its plots and state panels is a field of that topic's JSON schema (the app itself cannot be
run here: no display)."""

import json
import re
from pathlib import Path

from controller.episode.topics import JSON_SCHEMAS, TOPICS

LAYOUT = Path(__file__).resolve().parents[3] / "docs" / "foxglove" / "episode_layout.json"


def _paths(node):
    """Every ``value`` of a plot's or a state panel's ``paths`` in the layout."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key == "paths":
                yield from (p["value"] for p in value)
            else:
                yield from _paths(value)
    elif isinstance(node, list):
        for item in node:
            yield from _paths(item)


def test_every_message_path_in_the_layout_is_a_field_of_a_recorded_topic():
    layout = json.loads(LAYOUT.read_text())
    paths = list(_paths(layout["configById"]))
    assert len(paths) >= 5
    for path in paths:
        topic, field = re.fullmatch(r"(/[\w/]+)\.(\w+)(?:\[\d+\])?", path).groups()
        assert topic in TOPICS, path
        schema = JSON_SCHEMAS[TOPICS[topic].schema]
        assert field in schema["properties"], path


def test_the_image_and_3d_panels_name_recorded_topics():
    config = json.loads(LAYOUT.read_text())["configById"]
    image = next(v for k, v in config.items() if k.startswith("Image!"))
    assert image["imageMode"]["imageTopic"] in TOPICS
    scene = next(v for k, v in config.items() if k.startswith("3D!"))
    assert set(scene["topics"]) <= set(TOPICS) and "/tf" in scene["topics"]
