"""The real-time interface (port 30003, read-only 30013): its messages, decoded from the spec.

    from rtde_spec.realtime import decode, RealtimeStream
    values = decode(message_bytes, "5.10.0")      # {"q_actual": (...), "robot_mode": 7, ...}
    stream = RealtimeStream("3.15.0")
    for message in stream.feed(chunk): ...

Layouts per version live in spec/realtime/interface.yaml (compiled by codegen).
"""

from rtde_spec._generated.realtime import REALTIME_MAX_MESSAGE_BYTES, REALTIME_PORTS
from rtde_spec.realtime.codec import RealtimeStream, decode
from rtde_spec.realtime.layout import RealtimeLayout, known_sizes, layout_for, layout_for_size


def encode(values: dict, version: str) -> bytes:  # type: ignore[type-arg]
    """One message as a controller of `version` sends it; fields not given are zeros."""
    return layout_for(version).encode(values)


__all__ = [
    "REALTIME_MAX_MESSAGE_BYTES",
    "REALTIME_PORTS",
    "RealtimeLayout",
    "RealtimeStream",
    "decode",
    "encode",
    "known_sizes",
    "layout_for",
    "layout_for_size",
]
