"""MCAP output, the robotics log format Foxglove and the ROS tools open.

One channel per topic (a recipe's data packages, each other RTDE package, each
primary/secondary message and Robot State sub-package: see `topics`), JSON
messages with a JSON Schema generated from the spec, log times from the capture
time or the controller's timestamp. Written in zstd (else lz4, else plain) chunks
of about 1 MB, so memory stays bounded; the file appears at its name when closed
(see `Writer`), as MCAP's summary is written last. A recording's file (`live`) is in
place from its first batch on, each batch closing a chunk: a killed recorder leaves
every batch but the last in whole chunks, which MCAP readers read in order without
the summary (`mcap recover` writes the summary back).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import IO, TYPE_CHECKING, Any

from rtde_spec.errors import require
from rtde_spec.output.base import Writer

if TYPE_CHECKING:
    from rtde_spec.output.topics import Message

PROFILE = ""  # no ROS profile: plain JSON messages, which Foxglove reads by their JSON Schema
SCHEMA_ENCODING = "jsonschema"
MESSAGE_ENCODING = "json"


class _Counted:
    """The output as MCAP's writer wants it: it asks `tell()` for record offsets, which a pipe,
    stdout or a temporary part file cannot answer; the bytes written through here can."""

    def __init__(self, stream: IO[bytes]) -> None:
        self.stream = stream
        self.count = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        self.stream.write(data)
        self.count += len(data)
        return len(data)

    def tell(self) -> int:
        return self.count

    def flush(self) -> None:
        self.stream.flush()


def _compression(writer_module: Any) -> Any:
    kinds = writer_module.CompressionType
    for module, kind in (("zstandard", kinds.ZSTD), ("lz4", kinds.LZ4)):
        try:
            __import__(module)
        except ImportError:
            continue
        return kind
    return kinds.NONE


def _library() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return f"rtde_spec {version('rtde_spec')}"
    except PackageNotFoundError:
        return "rtde_spec"


class McapWriter(Writer):
    """Rows and columnar batches as MCAP messages; `topic` puts every row on one topic."""

    def __init__(self, stream: IO[bytes], *, topic: str | None = None, epoch: float | None = None) -> None:
        super().__init__(stream)
        mcap_writer = require("mcap.writer", "mcap", "MCAP output")
        from rtde_spec.output.topics import Topics  # the spec's layouts: loaded when MCAP is written

        self.topics = Topics(topic, epoch)
        self._out = _Counted(stream)
        self._mcap = mcap_writer.Writer(self._out, compression=_compression(mcap_writer))
        self._mcap.start(profile=PROFILE, library=_library())
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}

    @property
    def topic(self) -> str | None:
        """Every row on this topic (a capture table's file), else topics by content."""
        return self.topics.topic

    @topic.setter
    def topic(self, value: str | None) -> None:
        self.topics.topic = value

    def _channel(self, topic: str, schema: dict[str, Any]) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            data = json.dumps(schema, separators=(",", ":")).encode()
            schema_id = self._mcap.register_schema(name=schema["title"], encoding=SCHEMA_ENCODING, data=data)
            channel = self._mcap.register_channel(
                topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=schema_id
            )
            self._channels[topic] = channel
            self._sequence[channel] = 0
        return channel

    def _add(self, channel: int, data: bytes, log_time: int) -> None:
        sequence = self._sequence[channel]
        self._sequence[channel] = sequence + 1
        self._mcap.add_message(
            channel_id=channel, log_time=log_time, data=data, publish_time=log_time, sequence=sequence
        )

    def write(self, record: Mapping[str, Any]) -> None:
        for message in self.topics.messages(record):
            self._write_message(message)
        self.rows += 1

    def _write_message(self, message: Message) -> None:
        self._add(self._channel(message.topic, message.schema), message.data, message.log_time)

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        for topic, schema, lines, times in self.topics.column_messages(columns):
            channel = self._channel(topic, schema)
            for data, log_time in zip(lines, times.tolist(), strict=True):
                self._add(channel, data, log_time)
            self.rows += len(lines)

    def flush(self) -> None:
        """A live file's batch in a whole chunk on disk (a capture's tables keep ~1 MB chunks)."""
        if self.live and self.rows:
            finish_chunk = getattr(self._mcap, "flush", None)  # mcap 1.2 on
            if finish_chunk is not None:
                finish_chunk()
        super().flush()

    def size(self) -> int:
        """Bytes written so far; a chunk being filled (up to ~1 MB) is counted when written."""
        return self._out.count

    def _finish(self) -> None:
        self._mcap.finish()  # the summary and footer: what makes the file readable
        super()._finish()
