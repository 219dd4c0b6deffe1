"""What a person watching a robot wants from the primary/secondary stream: one line per
robot message, and the robot's modes only when they change (Robot State comes at 10 Hz).

Used by `rtde-spec watch`; usable on its own on any decoded message:

    changes = StateChanges()
    for message in client:                     # a PrimaryClient yields decoded messages
        print(describe_message(message) or changes.describe(message) or "", end="")

Both take one message; an `(offset, message)` pair (what `PrimaryStreamDecoder.feed`
and `PrimaryClient.messages(with_offsets=True)` yield) is refused with a UsageError
saying to unpack it, instead of being printed as a tuple.
"""

from __future__ import annotations

from typing import Any

from rtde_spec.errors import UsageError
from rtde_spec.output.describe import describe, enum_name
from rtde_spec.output.text import safe_text
from rtde_spec.wire.primary_base import OpaqueMessage, PrimaryModel, PrimaryPart, RobotStateMessage

# (sub-package, field) -> label: the modes and flags an operator acts on
WATCHED: dict[tuple[str, str], str] = {
    ("robot_mode_data", "robot_mode"): "robot mode",
    ("robot_mode_data", "control_mode"): "control mode",
    ("robot_mode_data", "is_robot_power_on"): "power on",
    ("robot_mode_data", "is_emergency_stopped"): "emergency stopped",
    ("robot_mode_data", "is_protective_stopped"): "protective stopped",
    ("robot_mode_data", "is_program_running"): "program running",
    ("robot_mode_data", "is_program_paused"): "program paused",
    ("robot_mode_data", "target_speed_fraction"): "speed slider",
    ("masterboard_data", "safety_mode"): "safety mode",
}


class StateChanges:
    """The watched modes of successive Robot States; reports what changed since the last one."""

    def __init__(self) -> None:
        self.values: dict[str, Any] = {}

    def update(self, message: Any) -> dict[str, str]:
        """label -> described new value, for every watched field that changed (all, the first time)."""
        _refuse_pair(message, "StateChanges.update")
        if not isinstance(message, RobotStateMessage):
            return {}
        changed: dict[str, str] = {}
        for (sub_name, field), label in WATCHED.items():
            sub = message.get(sub_name)
            value = getattr(sub, field, None) if sub is not None else None
            if value is None or self.values.get(label, _UNSEEN) == value:
                continue
            self.values[label] = value
            changed[label] = describe(value, getattr(type(sub), "ENUMS", {}).get(field))
        return changed

    def describe(self, message: Any) -> str | None:
        """'robot mode 7 (RUNNING) · program running True' for what changed, else None."""
        changed = self.update(message)
        return " · ".join(f"{k} {v}" for k, v in changed.items()) or None


_UNSEEN = object()


def code(part: PrimaryPart) -> str:
    """UR's error-code notation, C<code>A<argument>, as the log and the manuals write it."""
    return f"C{getattr(part, 'robot_message_code', '?')}A{getattr(part, 'robot_message_argument', '?')}"


def describe_message(message: Any) -> str | None:
    """One line for a message that is not Robot State (None for Robot State); wire text escaped."""
    _refuse_pair(message, "describe_message")
    parts = message_parts(message)
    return None if parts is None else f"{parts[0]}  {parts[1]}"


def message_parts(message: Any) -> tuple[str, str] | None:
    """(kind, text) of a message that is not Robot State, e.g. ("key", "C1A2 Title: ...")."""
    _refuse_pair(message, "message_parts")
    if isinstance(message, RobotStateMessage):
        return None
    name = getattr(message, "NAME", type(message).__name__)
    v = message
    if name == "version_message":
        number = f"{v.major_version}.{v.minor_version}.{v.bugfix_version}"
        build = f".{v.build_number}" if v.build_number is not None else ""
        text = f"{v.project_name} {number}{build} ({v.build_date})"
    elif name == "text_message":
        text = f"[{_enum(v, 'source')}] {v.text_message}"
    elif name == "robot_comm_message":
        level = _enum(v, "robot_message_report_level")
        text = f"{level} {code(v)} [{_enum(v, 'source')}] {v.report_text}"
    elif name == "key_message":
        text = f"{code(v)} {v.robot_message_title}: {v.key_text_message}"
    elif name == "safety_mode_message":
        text = f"{_enum(v, 'safety_mode_type')} {code(v)}"
    elif name == "runtime_exception_message":
        text = f"line {v.script_line_number}:{v.script_column_number}: {v.runtime_exception_text_message}"
    elif name == "request_value_message":
        text = f"#{v.request_id} ({_enum(v, 'requested_type')}): {v.request_text_message}"
    elif isinstance(message, OpaqueMessage):  # documented type, undocumented layout (Modbus info)
        name, text = message.family, f"{len(message.raw)} bytes: {message.raw.hex()}"
    else:
        text = _fields(message)
    return name.removesuffix("_message"), safe_text(text).replace("\n", "\\n")


def _refuse_pair(value: Any, where: str) -> None:
    """A UsageError for an (offset, message) pair given where one message belongs."""
    if isinstance(value, tuple) and not isinstance(value, PrimaryModel):
        kinds = ", ".join(type(v).__name__ for v in value[:3])
        raise UsageError(
            f"{where} takes one decoded message, not a tuple ({kinds}): unpack the "
            "(offset, message) pairs of PrimaryStreamDecoder.feed or "
            "PrimaryClient.messages(with_offsets=True), e.g. `for offset, message in ...`, "
            "or iterate the PrimaryClient itself, which yields messages"
        )


def _enum(part: Any, field: str) -> str:
    value = getattr(part, field)
    enum = getattr(type(part), "ENUMS", {}).get(field)
    named = enum_name(enum, value) if enum is not None and isinstance(value, int) else None
    return named or str(value)


def _fields(message: Any) -> str:
    """Every field as name=value (enum names where the spec has them): the general case."""
    if not isinstance(message, PrimaryModel):
        return str(message)
    values = message.values() if isinstance(message, PrimaryPart) else dict(message)
    enums: dict[str, str] = getattr(type(message), "ENUMS", {})
    shown = {k: v for k, v in values.items() if k not in ("timestamp", "source", "robot_message_type")}
    return " ".join(f"{k}={describe(v, enums.get(k))}" for k, v in shown.items())
