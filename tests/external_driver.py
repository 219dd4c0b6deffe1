"""The ROS driver's side of external control, as URCL's UrDriver plays it, for tests.

Written from spec/external_control/protocols.yaml: every record the driver writes or reads
on the reverse (50001), trajectory (50003) and script command (50004) ports is encoded and
decoded by rtde_spec.external's codecs, the multipliers the driver writes into its program
({{JOINT_STATE_REPLACE}}, {{TIME_REPLACE}}) are the spec's scales. The driver listens on
free ports (port 0) of a loopback address, so runs in parallel never collide, and sends the
robot its program headless: `stop program`, then the program wrapped in a `def`, on the
primary port, as URCL does (src/ur/ur_driver.cpp).

What the robot shows comes back on the controller's own ports: `PrimaryWatch` keeps the
primary port's Robot State (robot mode, joints, program running) and the text messages and
runtime exceptions the program sends there.
"""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rtde_spec.external.codec import RecordCodec, record_codec
from rtde_spec.metamodel.external import external_spec
from rtde_spec.primary.client import PrimaryClient

PROGRAM = Path(__file__).parent / "data" / "external_control_driver.urscript"
PLACEHOLDER = re.compile(r"\{\{(\w+)\}\}")
SERVOJ_ARGUMENTS = "lookahead_time=0.03, gain=2000"  # URCL's defaults, as its driver writes them
PORT_NAMES = ("reverse", "trajectory", "script_command")


def _scale(protocol: str, message: str, variant: str, name: str) -> int:
    """A field's multiplier as the spec gives it (the wire holds value x scale)."""
    for m in external_spec().protocol(protocol).messages:
        if m.name != message:
            continue
        for v in m.variants:
            if v.name == variant:
                scale = next(f.scale for f in v.fields if f.name == name)
                assert scale is not None
                return int(scale)
    raise KeyError(f"{protocol}.{message}.{variant}.{name}")


MULT_JOINTSTATE = _scale("reverse", "reverse_command", "motion_target", "target")
MULT_TIME = _scale("trajectory", "trajectory_point", "motion_primitive", "duration")


def render(template: str, host: str, ports: Mapping[str, int], servoj: str = SERVOJ_ARGUMENTS) -> str:
    """The program with each {{NAME}} filled as URCL's ScriptReader fills it; an unknown one is an error."""
    values = {
        "BEGIN_REPLACE": "",
        "JOINT_STATE_REPLACE": str(MULT_JOINTSTATE),
        "TIME_REPLACE": str(MULT_TIME),
        "SERVO_J_REPLACE": servoj,
        "SERVER_IP_REPLACE": host,
        "SERVER_PORT_REPLACE": str(ports["reverse"]),
        "TRAJECTORY_SERVER_PORT_REPLACE": str(ports["trajectory"]),
        "SCRIPT_COMMAND_SERVER_PORT_REPLACE": str(ports["script_command"]),
    }

    def fill(match: re.Match[str]) -> str:
        if match.group(1) not in values:
            raise KeyError(f"the program names {match.group(0)}, which the driver does not fill")
        return values[match.group(1)]

    return PLACEHOLDER.sub(fill, template)


def headless(program: str) -> str:
    """What URCL sends on the primary port in headless mode: stop, then the program in a def."""
    body = "".join(f"\t{line}\n" for line in program.splitlines())
    return f"stop program\ndef externalControl():\n{body}end\n"


class PrimaryWatch:
    """The primary port as the driver's primary client reads it, in a thread of its own.

    Keeps the latest robot mode data and joint data, and every text message and runtime
    exception in arrival order; `send` writes plain commands or programs to the same port.
    """

    def __init__(self, host: str, port: int) -> None:
        self.client = PrimaryClient(host, port, timeout=10.0).connect()
        self.lock = threading.RLock()
        self.mode: Any = None
        self.joints: Any = None
        self.texts: list[str] = []
        self.exceptions: list[str] = []
        self.reader = threading.Thread(target=self._read, name="primary-watch", daemon=True)
        self.reader.start()

    def _read(self) -> None:
        try:
            for message in self.client:
                self._keep(message)
        except (OSError, ValueError):
            return  # closed under the reader

    def _keep(self, message: Any) -> None:
        with self.lock:
            if message.NAME == "robot_state":
                for part in message.sub_packages:
                    if type(part).__name__ == "RobotModeData":
                        self.mode = part
                    elif type(part).__name__ == "JointData":
                        self.joints = part
            elif hasattr(message, "text_message"):
                self.texts.append(str(message.text_message))
            elif type(message).__name__ == "RuntimeExceptionMessage":
                self.exceptions.append(str(message))

    def send(self, text: str) -> None:
        self.client.send_script(text)

    def wait(self, done: Callable[[PrimaryWatch], bool], seconds: float, what: str) -> None:
        deadline = time.monotonic() + seconds
        while True:
            with self.lock:
                if done(self):
                    return
            if time.monotonic() > deadline:
                with self.lock:
                    raise AssertionError(
                        f"{what}: not within {seconds} s (texts {self.texts[-8:]}, "
                        f"exceptions {self.exceptions})"
                    )
            time.sleep(0.01)

    def wait_text(self, text: str, seconds: float = 5.0) -> None:
        self.wait(lambda w: any(text in t for t in w.texts), seconds, f"text {text!r}")

    @property
    def q(self) -> list[float]:
        with self.lock:
            assert self.joints is not None
            return [j.q_actual for j in self.joints.joints]

    def close(self) -> None:
        self.client.close()
        self.reader.join(5)


class DriverSide:
    """URCL's three servers of external control (reverse, trajectory, script command) on free
    ports, and the records it writes on them, encoded from the spec."""

    def __init__(self, host: str = "127.0.0.1") -> None:
        self.host = host
        self.servers = {name: socket.create_server((host, 0)) for name in PORT_NAMES}
        self.ports = {name: s.getsockname()[1] for name, s in self.servers.items()}
        self.robot: dict[str, socket.socket] = {}
        self.reverse_codec = record_codec("reverse", "reverse_command")
        self.point_codec = record_codec("trajectory", "trajectory_point")
        self.result_codec = record_codec("trajectory", "trajectory_result")
        self.command_codec = record_codec("script_command", "script_command")
        self.contact_codec = record_codec("script_command", "tool_contact_result")

    def program(self, template: str | None = None) -> str:
        """The headless program for these ports (default: tests/data/external_control_driver.urscript)."""
        return headless(render(template or PROGRAM.read_text(), self.host, self.ports))

    def accept(self, seconds: float = 10.0) -> None:
        """Wait until the robot's program has connected to all three servers."""
        deadline = time.monotonic() + seconds
        for name in PORT_NAMES:
            server = self.servers[name]
            server.settimeout(max(0.01, deadline - time.monotonic()))
            try:
                conn, _ = server.accept()
            except TimeoutError:
                raise AssertionError(f"the robot's program never connected to the {name} port") from None
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.settimeout(seconds)
            self.robot[name] = conn

    # --- the reverse interface (50001) ----------------------------------------------------

    def write_command(self, values: Sequence[float], mode: int, read_timeout: float = 0.1) -> None:
        """A motion target (servoj, speedj, speedl, pose, or IDLE / STOPPED with zeros)."""
        record = {"read_timeout": read_timeout, "target": list(values), "control_mode": mode}
        self.robot["reverse"].sendall(self.reverse_codec.encode("motion_target", record))

    def keepalive(self, read_timeout: float = 1.0) -> None:
        """URCL's keepalive: an IDLE record with the robot's next read timeout."""
        self.write_command([0.0] * 6, self.mode("IDLE"), read_timeout)

    def trajectory_control(self, action: str, points: int = 0, read_timeout: float = 1.0) -> None:
        record = {
            "read_timeout": read_timeout,
            "trajectory_action": self.value("TrajectoryControlMessage", action),
            "point_count": points,
            "move_id": 0,
            "unused": [0, 0, 0],
            "control_mode": self.mode("FORWARD"),
        }
        self.robot["reverse"].sendall(self.reverse_codec.encode("trajectory_control", record))

    # --- the trajectory interface (50003) -------------------------------------------------

    def write_point(
        self, kind: str, target: Sequence[float], duration: float = 0.0, velocity: float = 1.0,
        acceleration: float = 1.0, blend: float = 0.0,
    ) -> None:  # fmt: skip
        """A motion primitive (MOVEJ: joints, MOVEL: a pose) with its timing."""
        record = {
            "target": list(target),
            "via_or_q_near": [0.0] * 6,
            "velocity": velocity,
            "acceleration": acceleration,
            "mode_or_has_q_near": 0.0,
            "unused": [0, 0, 0],
            "duration": duration,
            "blend_radius": blend,
            "motion_type": self.value("MotionType", kind),
        }
        self.robot["trajectory"].sendall(self.point_codec.encode("motion_primitive", record))

    def write_spline_point(
        self, positions: Sequence[float], velocities: Sequence[float], duration: float
    ) -> None:
        record = {
            "positions": list(positions),
            "velocities": list(velocities),
            "accelerations": [0.0] * 6,
            "duration": duration,
            "spline_type": self.value("SplineType", "CUBIC"),
            "motion_type": self.value("MotionType", "SPLINE"),
        }
        self.robot["trajectory"].sendall(self.point_codec.encode("spline_point", record))

    def trajectory_result(self, seconds: float = 10.0) -> str:
        """The result word the robot sends when a trajectory ends, by its enum name; meanwhile a
        NOOP trajectory control message every 0.1 s keeps the program's reverse read fed, as
        URCL's examples do while they wait."""
        return self._answer(
            "trajectory", self.result_codec, "TrajectoryResult", seconds,
            lambda: self.trajectory_control("NOOP"),
        )  # fmt: skip

    # --- the script command interface (50004) ---------------------------------------------

    def script_command(self, variant: str, **values: Any) -> None:
        """One script command (a variant of the spec's script_command, its fields by name)."""
        name = variant.upper()
        if name == "ZERO_FT_SENSOR":
            name = "ZERO_FTSENSOR"
        record = {"command": self.value("ScriptCommand", name), **values}
        self.robot["script_command"].sendall(self.command_codec.encode(variant, record))

    def tool_contact_result(self, seconds: float = 5.0) -> str:
        return self._answer(
            "script_command", self.contact_codec, "ToolContactResult", seconds, self.keepalive
        )

    # --- helpers ------------------------------------------------------------------------------

    def _answer(
        self, port: str, codec: RecordCodec, enum: str, seconds: float, keep: Callable[[], None]
    ) -> str:
        """One record from the robot on `port`, calling `keep` every 0.1 s until it is whole."""
        conn = self.robot[port]
        conn.settimeout(0.1)
        deadline = time.monotonic() + seconds
        data = b""
        while len(data) < codec.size:
            try:
                chunk = conn.recv(codec.size - len(data))
            except TimeoutError:
                if time.monotonic() > deadline:
                    raise AssertionError(f"no answer on the {port} socket within {seconds} s") from None
                keep()
                continue
            if not chunk:
                raise AssertionError(f"the robot closed the {port} socket before answering")
            data += chunk
        _, values = codec.decode(data)
        return self.enum_name(enum, values["result"])

    @staticmethod
    def value(enum: str, name: str) -> int:
        spec = next(e for e in external_spec().enums if e.name == enum)
        return next(v.value for v in spec.values if v.name == name)

    @staticmethod
    def enum_name(enum: str, value: int) -> str:
        spec = next(e for e in external_spec().enums if e.name == enum)
        return next((v.name for v in spec.values if v.value == value), str(value))

    def mode(self, name: str) -> int:
        return self.value("UrclControlMode", name)

    def closed_by_robot(self, port: str, seconds: float = 5.0) -> bool:
        """Whether the robot closed its end of `port` (what arrives before the end is dropped)."""
        conn = self.robot[port]
        conn.settimeout(seconds)
        try:
            while conn.recv(4096):
                pass
        except TimeoutError:
            return False
        except OSError:
            return True
        return True

    def close(self) -> None:
        for conn in self.robot.values():
            conn.close()
        for server in self.servers.values():
            server.close()

    def __enter__(self) -> DriverSide:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def straight(start: Iterable[float], end: Iterable[float], fraction: float) -> list[float]:
    return [a + (b - a) * fraction for a, b in zip(start, end, strict=True)]
