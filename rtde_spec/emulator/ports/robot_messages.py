"""Robot messages a controller sends when things happen, built from the spec's models.

The Version message opens every primary/secondary connection; the rest go to the
primary ports only (30001, 30011), as the interface document says: a text message
for `textmsg` (and popups, which the spec has no message for), a runtime exception
with the script line and column, a key message when a program starts or stops
(PROGRAM_XXX_STARTED / PROGRAM_XXX_STOPPED with the program's name, as controllers
announce it: the name runs to the end of the message, see key_message) followed on
start by the global variables setup message (the program's global variable names), the
global variables update (their values) every 100 ms while it runs, and a safety mode
message whenever the safety mode changes.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

from rtde_spec._generated.enums import (
    MessageSource,
    ReportDataType,
    ReportLevel,
)
from rtde_spec.emulator.urscript.matrices import is_matrix
from rtde_spec.emulator.urscript.values import INT_MAX, INT_MIN, Pose
from rtde_spec.metamodel.versions import Version
from rtde_spec.primary import models as pm
from rtde_spec.primary.codec import default_codec, encode_message
from rtde_spec.wire.primary_values import VariableValue

PROJECT = "URControl"
BUILD_DATE = "emulated by rtde_spec"
PROGRAM_STARTED, PROGRAM_STOPPED = "PROGRAM_XXX_STARTED", "PROGRAM_XXX_STOPPED"
_INTERFACE = int(MessageSource.ROBOTINTERFACE)
_CONTROLLER = int(MessageSource.CONTROLLER)


def _built(cls: Any, micros: int, **fields: Any) -> bytes:
    """A message of model `cls`, stamped `micros`, with the type tag the spec gives its model."""
    return encode_message(cls(timestamp=micros, robot_message_type=cls.TYPE, **fields))


def prepare() -> None:
    """Build the primary codec these messages are encoded with, before the control loop needs it.

    It is made on first use and costs some 40 ms (its models and decoders are compiled): made at a
    program's first key message, inside a control step, it held the loop up for 20 e-Series steps
    (5 CB3 ones) just after a client's program started, and the RTDE packages of those steps left
    late in a burst."""
    default_codec()


def version_message(version: Version, micros: int) -> bytes:
    return _built(
        pm.VersionMessage,
        micros,
        source=_INTERFACE,
        project_name=PROJECT,
        major_version=version.major,
        minor_version=version.minor,
        bugfix_version=version.bugfix,
        build_number=version.build or 0,
        build_date=BUILD_DATE,
    )


def text_message(text: str, micros: int) -> bytes:
    return _built(
        pm.TextMessage,
        micros,
        source=_INTERFACE,
        text_message=text,
    )


def runtime_exception(text: str, line: int, column: int, micros: int) -> bytes:
    return _built(
        pm.RuntimeExceptionMessage,
        micros,
        source=_INTERFACE,
        script_line_number=max(0, line),
        script_column_number=max(0, column),
        runtime_exception_text_message=text,
    )


def error_code_message(code: int, argument: int, level: int, micros: int) -> bytes:
    """An Error Code (Robot Comm) message: code and argument as URCL reads them (C209A0)."""
    return _built(
        pm.RobotCommMessage,
        micros,
        source=_CONTROLLER,
        robot_message_code=code,
        robot_message_argument=argument,
        robot_message_report_level=level,
        data_type=int(ReportDataType.UINT32),
        report_data=0,
        report_text="",
    )


def key_message(title: str, text: str, micros: int) -> bytes:
    """A key message as controllers send it: the text runs to the end of the message, with no
    length before it (UR's C++ client library reads it so and matches the program's name against
    it; the spec's decoder takes this form as its fallback, see key_text_message in the spec)."""
    head = _built(
        pm.KeyMessage,
        micros,
        source=_CONTROLLER,
        robot_message_code=0,
        robot_message_argument=0,
        robot_message_title=title,
        key_text_message="",
    )[:-2]  # the document's uint16 length of an empty text
    body = head[4:] + text.encode("utf-8")
    return struct.pack(">I", 4 + len(body)) + body


def safety_mode_message(mode: int, micros: int) -> bytes:
    return _built(
        pm.SafetyModeMessage,
        micros,
        source=_CONTROLLER,
        robot_message_code=0,
        robot_message_argument=0,
        safety_mode_type=mode,
        report_data_type=int(ReportDataType.UINT32),
        report_data=0,
    )


def program_threads_message(labels: list[tuple[str, int, str]], micros: int) -> bytes:
    """Program Threads (14): each running thread's last label (`$ N "text"`) as (thread, N, text)."""
    return _built(
        pm.ProgramThreadsMessage,
        micros,
        source=_CONTROLLER,
        threads=[
            pm.ProgramThread(label_id=number, label_name=text[:255], thread_name=thread[:65535])
            for thread, number, text in labels
        ],
    )


def global_variables_setup(names: list[str], micros: int) -> bytes:
    return _built(
        pm.GlobalVariablesSetupMessage,
        micros,
        start_index=0,
        variable_names=names,
    )


# bytes of values one Global Variables Update carries at most (the emulator's bound: no document gives
# one; a string's most, 64 kB, fits): a program holding megabytes in its globals costs the control
# step no more than this a tick
UPDATE_BYTES = 128 << 10


def global_variables_update(values: Sequence[Any], micros: int, start: int = 0) -> tuple[bytes, int]:
    """Global Variables Update: the values from `start` on, in the order of the setup message's names,
    as many as fit UPDATE_BYTES (its start index says where they begin; the next update goes on from
    there). A name the program has not written yet, a value of no listed type, or one too big for an
    update alone is NONE. Returns the message and the index the next update starts at."""
    picked: list[Any] = []
    used, at = 0, start
    while at < len(values):
        size = value_size(values[at], UPDATE_BYTES - used)
        if picked and used + size > UPDATE_BYTES:
            break
        picked.append(values[at] if size <= UPDATE_BYTES else None)
        used, at = used + min(size, UPDATE_BYTES), at + 1
    message = _built(
        pm.GlobalVariablesUpdateMessage,
        micros,
        start_index=start,
        variable_values=[typed(value) for value in picked],
    )
    return message, (at if at < len(values) else 0)


def value_size(value: Any, limit: int) -> int:
    """About the bytes `value` takes in an update, counted no further than just past `limit`."""
    if isinstance(value, str):
        return 3 + min(len(value), 65535)
    if isinstance(value, list):
        total = 3
        for item in value:
            total += value_size(item, limit - total)
            if total > limit:
                break
        return total
    return 25  # a number, a bool or a pose (six floats) and its type byte


def typed(value: Any) -> VariableValue:
    """A URScript value as the update message types it (spec/primary/enums.yaml GlobalVariableType)."""
    if isinstance(value, bool):
        return VariableValue(type="BOOL", value=value)
    if isinstance(value, int) and INT_MIN <= value <= INT_MAX:
        return VariableValue(type="INT", value=value)
    if isinstance(value, (int, float)):
        return VariableValue(type="FLOAT", value=float(value))
    if isinstance(value, str):
        return VariableValue(type="VAR_STRING", value=value[:65535])
    if isinstance(value, Pose):
        return VariableValue(type="POSE", value=tuple(float(v) for v in value))
    if is_matrix(value):
        return VariableValue(type="MATRIX", value=[[typed(v) for v in row] for row in value])
    if isinstance(value, list) and len(value) <= 65535:
        return VariableValue(type="LIST", value=[typed(v) for v in value])
    return VariableValue(type="NONE", value=None)


def event_messages(event: Any, micros: int) -> list[bytes]:
    """The messages for one model event (emulator/urscript/events.py's ScriptEvent)."""
    kind = getattr(event, "kind", "")
    text = str(getattr(event, "text", ""))
    if kind == "runtime_exception":
        return [runtime_exception(text, int(event.line), int(event.column), micros)]
    if kind == "text":
        return [text_message(text, micros)]
    if kind == "popup":
        title = str(getattr(event, "title", "") or "Popup")
        return [text_message(f"{title}: {text}", micros)]
    if kind == "program_started":
        return [
            key_message(PROGRAM_STARTED, event.program or text, micros),
            global_variables_setup(list(getattr(event, "names", ())), micros),
        ]
    if kind == "program_stopped":
        return [key_message(PROGRAM_STOPPED, event.program or text, micros)]
    if kind == "error_code":
        level = ReportLevel.WARNING if event.warning else ReportLevel.VIOLATION
        return [error_code_message(int(event.code), int(event.argument), int(level), micros)]
    return []
