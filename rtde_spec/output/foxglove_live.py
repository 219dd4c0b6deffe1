"""The live view: a Foxglove WebSocket server publishing what a robot sends, as it arrives.

The same topics, JSON messages and spec-generated schemas as an MCAP file (see
`topics`), so a layout made for a recording works live and back. The TCP pose
(RTDE `actual_TCP_pose`, or a Robot State's `cartesian_info`) is also published
as a `foxglove.FrameTransform` from frame `base` to frame `tool` on `/tf`, so the
3D panel shows the tool moving. Log times: the controller's timestamp, offset to
the wall clock at the first message (see `topics.Clock`).

foxglove-sdk is imported when a server starts; nothing else imports it.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping, Sequence
from typing import Any

from rtde_spec.errors import UsageError, require

DEFAULT_PORT = 8765  # the port the Foxglove app tries first for a WebSocket connection
TF_TOPIC = "/tf"
BASE_FRAME, TOOL_FRAME = "base", "tool"
TCP_POSE = "actual_TCP_pose"  # RTDE output: x, y, z [m], rotation vector rx, ry, rz [rad]
CARTESIAN_INFO = "/primary/cartesian_info"  # Robot State sub-package with the same pose as x..rz
_POSE_KEYS = ("x", "y", "z", "rx", "ry", "rz")


def quaternion(rx: float, ry: float, rz: float) -> tuple[float, float, float, float]:
    """A rotation vector (axis times angle, as UR poses give it) as a quaternion (x, y, z, w)."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    if angle < 1e-12:
        return (0.0, 0.0, 0.0, 1.0)
    s = math.sin(angle / 2) / angle
    return (rx * s, ry * s, rz * s, math.cos(angle / 2))


class LivePublisher:
    """A Foxglove WebSocket server on `port` (0: any free port; `port` then says which).

    `publish_row` takes the rows the writers take (an RTDE package, a primary
    message as JSON, a recipe's values); `publish_record` a data package record
    from `RtdeClient.on_data`. Safe to call from several threads (an RTDE reader
    thread and a primary loop).
    """

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1", name: str = "rtde-spec") -> None:
        foxglove = require("foxglove", "foxglove", "the Foxglove live view")
        from foxglove.channels import FrameTransformChannel

        from rtde_spec.output.topics import Topics

        self._foxglove = foxglove
        self._context = foxglove.Context()  # this server's channels only
        try:
            self.server = foxglove.start_server(name=name, host=host, port=port, context=self._context)
        except Exception as exc:  # the SDK's own error (port in use, no such address)
            raise UsageError(f"cannot serve the live view on {host}:{port}: {exc}") from exc
        self.host = host
        self.port: int = self.server.port
        self._lock = threading.Lock()
        self._topics = {"rtde": Topics(protocol="rtde"), "primary": Topics(protocol="primary")}
        self._clock = self._topics["rtde"].clock
        self._topics["primary"].clock = self._clock  # one time line for both interfaces
        self._channels: dict[str, Any] = {}
        self._tf = FrameTransformChannel(TF_TOPIC, context=self._context)
        self.published = 0

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def publish_row(self, row: Mapping[str, Any], protocol: str = "rtde") -> None:
        """One row: its messages on their topics, and the tool frame if it holds the TCP pose."""
        with self._lock:
            for message in self._topics[protocol].messages(row):
                self._channel(message.topic, message.schema).log(message.data, log_time=message.log_time)
                self.published += 1
                self._frame(message.topic, row, message.data, message.log_time)

    def publish_record(self, record: Any, recipe_id: int | None = None) -> None:
        """A data package record (`RtdeClient.on_data`): on `/rtde/outputs/<recipe id>`."""
        row = record._asdict() if hasattr(record, "_asdict") else dict(record)
        self.publish_row({"recipe_id": recipe_id, **row} if recipe_id is not None else row)

    def _channel(self, topic: str, schema: dict[str, Any]) -> Any:
        channel = self._channels.get(topic)
        if channel is None:
            schema_obj = self._foxglove.Schema(
                name=schema["title"], encoding="jsonschema", data=_json(schema)
            )
            channel = self._foxglove.Channel(
                topic, schema=schema_obj, message_encoding="json", context=self._context
            )
            self._channels[topic] = channel
        return channel

    def _frame(self, topic: str, row: Mapping[str, Any], data: bytes, log_time: int) -> None:
        pose: Sequence[Any] | None = None
        if TCP_POSE in row and topic.startswith("/rtde/"):
            pose = row[TCP_POSE]
        elif topic == CARTESIAN_INFO:
            import json

            body = json.loads(data)
            pose = [body.get(k) for k in _POSE_KEYS]
        if pose is not None and len(pose) == 6 and all(isinstance(v, (int, float)) for v in pose):
            self.publish_pose([float(v) for v in pose], log_time)

    def publish_pose(self, pose: Sequence[float], log_time: int | None = None) -> None:
        """The tool's frame in the base frame, from a UR pose (x, y, z, rx, ry, rz)."""
        from foxglove.messages import FrameTransform, Quaternion, Timestamp, Vector3

        when = log_time if log_time is not None else self._clock.unknown()
        qx, qy, qz, qw = quaternion(pose[3], pose[4], pose[5])
        transform = FrameTransform(
            timestamp=Timestamp(sec=when // 1_000_000_000, nsec=when % 1_000_000_000),
            parent_frame_id=BASE_FRAME,
            child_frame_id=TOOL_FRAME,
            translation=Vector3(x=pose[0], y=pose[1], z=pose[2]),
            rotation=Quaternion(x=qx, y=qy, z=qz, w=qw),
        )
        self._tf.log(transform, log_time=when)

    def close(self) -> None:
        """Stop the server; clients see the connection close."""
        self.server.stop()

    def __enter__(self) -> LivePublisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _json(value: Any) -> bytes:
    import json

    return json.dumps(value, separators=(",", ":")).encode()
