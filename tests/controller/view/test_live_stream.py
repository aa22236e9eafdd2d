"""The Foxglove live stream: a local WebSocket client subscribes and receives one message of
each schema, whichever subprotocol name it offers: foxglove-sdk 0.30's server accepts only
``foxglove.sdk.v1``, and the stream's relay serves a client offering only the older
``foxglove.websocket.v1`` (Lichtblick, the Foxglove app of before the SDK) too; the messages
are the same (JSON ``advertise`` and ``subscribe``, binary ``MessageData``: opcode 1,
subscription id u32, log time u64, payload). Failures to listen are one line saying why."""

import json
import struct

import numpy as np
import pytest
from websockets.sync.client import connect

from controller.episode import foxglove_types, topics
from controller.episode.writer import json_bytes
from controller.tactile.field import VectorField
from controller.view.live_stream import FoxgloveLiveStream, LiveStreamError

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
BINARY_MESSAGE_DATA = 0x01


def records():
    """One record of each schema: the three protobuf ones and a JSON one."""
    field = VectorField(np.linspace(-3, 3, 4), np.linspace(-2, 2, 3), np.zeros((3, 4)),
                        np.zeros((3, 4)))  # fmt: skip
    image = np.full((24, 32, 3), 100, np.uint8)
    return {
        topics.TACTILE_IMAGE.name: (topics.TACTILE_IMAGE,
                                    foxglove_types.image_bytes(1.0, image, "jpeg", 80)),
        topics.TACTILE_FIELD.name: (topics.TACTILE_FIELD, foxglove_types.grid_bytes(1.0, field)),
        topics.TCP_TF.name: (topics.TCP_TF, foxglove_types.transforms_bytes(
            1.0, [("B", "T", np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))])),
        topics.TRANSITION.name: (topics.TRANSITION, json_bytes(
            {"t_s": 1.0, "from": "grasp", "to": "teleop", "reason": "grasped_and_zeroed"})),
    }  # fmt: skip


@pytest.mark.parametrize(
    "offered", [SUBPROTOCOLS, ["foxglove.websocket.v1"], ["foxglove.sdk.v1"]], ids=str
)
def test_a_client_subscribes_and_receives_each_schema(offered):
    stream = FoxgloveLiveStream(port=0)
    try:
        sent = records()
        for topic, data in sent.values():  # the channels open as their topics first appear
            stream(topic, 1_000_000_000, None, data)
        with connect(stream.url, subprotocols=offered, open_timeout=5) as ws:
            assert ws.subprotocol == offered[0]
            channels = {}
            while len(channels) < len(sent):
                message = json.loads(ws.recv(timeout=5))
                if message["op"] == "advertise":
                    channels.update({c["topic"]: c for c in message["channels"]})
            assert channels[topics.TACTILE_IMAGE.name]["schemaName"] == "foxglove.CompressedImage"
            assert channels[topics.TRANSITION.name]["encoding"] == "json"
            assert channels[topics.TRANSITION.name]["schemaEncoding"] == "jsonschema"
            subscriptions = {i: name for i, name in enumerate(sent)}
            ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": i, "channelId": channels[name]["id"]} for i, name in subscriptions.items()
            ]}))  # fmt: skip
            received = {}
            for _ in range(50):
                if len(received) == len(sent):
                    break
                for topic, data in sent.values():  # keep logging until each arrives
                    stream(topic, 2_000_000_000, None, data)
                try:
                    frame = ws.recv(timeout=0.5)
                except TimeoutError:
                    continue
                while isinstance(frame, bytes):
                    assert frame[0] == BINARY_MESSAGE_DATA
                    sub, log_time = struct.unpack_from("<IQ", frame, 1)
                    received[subscriptions[sub]] = (log_time, frame[13:])
                    try:
                        frame = ws.recv(timeout=0.05)
                    except TimeoutError:
                        break
        assert set(received) == set(sent)
        for name, (log_time, payload) in received.items():
            assert payload == sent[name][1]  # the very bytes the episode file gets
            assert log_time in (1_000_000_000, 2_000_000_000)
    finally:
        stream.close()


def test_a_port_already_taken_is_one_clear_error():
    first = FoxgloveLiveStream(port=0)
    try:
        with pytest.raises(LiveStreamError, match=f"127.0.0.1:{first.port}: the port is taken"):
            FoxgloveLiveStream(port=first.port)
    finally:
        first.close()


def test_a_bad_host_name_is_not_blamed_on_the_port():
    with pytest.raises(LiveStreamError) as error:
        FoxgloveLiveStream(host="no-such-host.invalid", port=0)
    assert "does not resolve" in str(error.value) and "port" not in str(error.value).split(":")[-1]


def test_an_ipv6_host_is_written_in_brackets():
    try:
        stream = FoxgloveLiveStream(host="::1", port=0)
    except LiveStreamError:
        pytest.skip("no IPv6 loopback on this machine")
    try:
        assert stream.url == f"ws://[::1]:{stream.port}"
        with connect(stream.url, subprotocols=SUBPROTOCOLS, open_timeout=5) as ws:
            assert json.loads(ws.recv(timeout=5))["op"] == "serverInfo"
    finally:
        stream.close()
