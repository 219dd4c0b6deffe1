"""Make the shipped `driver.pcap`: a ROS-driver-like client's session with the emulator, captured.

A capture of a driver session is what users bring, so the example is one: `rtde-spec serve` runs
in its own process on a loopback address as the robot, and a client shaped like UR's client
library (URCL, the core of the ROS drivers) in headless mode talks to it on every port it uses:
the dashboard (29999), the primary interface (30001: it reads the robot state and sends the
external-control program there), RTDE (30004: version, recipes, inputs, data), and the ports the
program connects back to on the driver's PC (50001 reverse: servoj targets, then trajectory
control; 50003 trajectory: points one way, the result the other; 50004 script commands). dumpcap
records the loopback traffic. The program is our own, in the shape of URCL's
external_control.urscript (the lines a capture reads its layout from are there).

Run once at development time (dumpcap, from Debian's tshark package, and the right to capture on
`lo`): `python -m rtde_spec.examples.make_driver_capture` rewrites rtde_spec/examples/files/driver.pcap;
`-o PATH` writes elsewhere. tests/test_examples.py holds the shipped file to what this session
sends; tests/test_driver_session.py runs the session itself.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from rtde_spec import RtdeClient
from rtde_spec.output.partfile import Part

# A driver beside a simulator on one machine: both on 127.0.0.1 (a robot's program connects back
# from the machine's own address, so a loopback address of its own would not show on those ports)
ROBOT = DRIVER = "127.0.0.1"
MULT = 1_000_000  # URCL's MULT_JOINTSTATE and MULT_TIME (microseconds) since its pull request 482
CONTROLLER, MODEL = "5.15.0", "UR5e"
RTDE_FREQUENCY = 125.0  # the driver's rate on a CB3; e-Series drivers ask 500 Hz (4x the file size)
OUTPUTS = [  # a part of ur_robot_driver's rtde_output_recipe.txt
    "timestamp", "actual_q", "actual_qd", "speed_scaling", "target_speed_fraction", "runtime_state",
    "actual_TCP_pose", "robot_mode", "safety_mode",
]  # fmt: skip
INPUTS = ["speed_slider_mask", "speed_slider_fraction"]  # the driver's speed slider recipe
DASHBOARD = [
    "PolyscopeVersion",
    "power on",
    "brake release",
    "robotmode",
    "safetystatus",
    "is in remote control",
]
SHIPPED = Path(__file__).resolve().parent / "files" / "driver.pcap"

# The robot's side: our own program in the shape of URCL's external_control.urscript
PROGRAM = "".join(
    line for line in resources.files(__package__).joinpath("external_control.script").read_text("utf-8")
    .splitlines(keepends=True) if not line.startswith("#")
)  # fmt: skip

HOME = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
SERVO_STEPS = 150  # 0.3 s of servoj targets at 500 Hz
TRAJECTORY = [  # (joint target, velocity rad/s, acceleration rad/s^2, duration s, blend m)
    ((0.3, -1.4, 1.4, -1.5, -1.5708, 0.2), 1.05, 1.4, 0.0, 0.0),
    ((0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0), 1.05, 1.4, 1.0, 0.0),
]
PAYLOAD = (1.5, (0.0, 0.0, 0.05))  # kg, m


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def scaled(values: tuple[float, ...], mult: int = MULT) -> list[int]:
    return [round(v * mult) for v in values]


def servoj(q: tuple[float, ...], timeout_ms: int = 500) -> bytes:
    """(URCL's default read time-out is 20 ms; a loaded machine's Python misses that now and then)"""
    return words(timeout_ms, *scaled(q), 1)  # read timeout, six targets, MODE_SERVOJ


def movej_point(
    q: tuple[float, ...], velocity: float, acceleration: float, duration: float, blend: float
) -> bytes:
    """A MOVEJ motion primitive of URCL's newest trajectory layout: 21 words."""
    return words(*scaled(q), *[0] * 6, *scaled((velocity, acceleration, 0.0)), 0, 0, 0,
                 round(duration * MULT), round(blend * MULT), 0)  # fmt: skip


@dataclass
class Ports:
    """Where each side listens: the controller's and the driver's defaults, or 0 for free ports."""

    dashboard: int = 29999
    primary: int = 30001
    secondary: int = 30002
    realtime: int = 30003
    rtde: int = 30004
    reverse: int = 50001
    trajectory: int = 50003
    script_command: int = 50004


@dataclass
class Session:
    """What the driver saw, for a test to hold the session to."""

    dashboard: list[tuple[str, str]] = field(default_factory=list)
    rtde_rows: int = 0
    primary: bytearray = field(default_factory=bytearray)  # what the primary port sent the driver
    trajectory_result: int | None = None
    program_closed: bool = False
    robot_log: list[str] = field(default_factory=list)

    def robot_messages(self) -> list[str]:
        """The robot's messages on the primary port (the program's textmsg among them), one line each."""
        from rtde_spec import PrimaryStreamDecoder
        from rtde_spec.primary.events import describe_message

        lines = [describe_message(m) for _, m in PrimaryStreamDecoder().feed(bytes(self.primary))]
        return [line for line in lines if line is not None]


@contextlib.contextmanager
def robot(host: str, ports: Ports, log: list[str]) -> Iterator[dict[str, int]]:
    """`rtde-spec serve` in its own process, as a robot is; yields the ports it serves, its log to `log`."""
    args = [sys.executable, "-m", "rtde_spec", "serve", "--host", host, "--controller", CONTROLLER,
            "--model", MODEL]  # fmt: skip
    for name in ("dashboard", "primary", "secondary", "realtime", "rtde"):
        args += [f"--{name}-port", str(getattr(ports, name))]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde 30004, primary 30001, ..."
        if "emulating controller" not in line:
            raise RuntimeError(f"the emulator did not start: {proc.stderr.read() if proc.stderr else line}")
        threading.Thread(target=lambda: log.extend(iter(proc.stderr.readline, "")), daemon=True).start()  # type: ignore[union-attr]
        yield {name: int(port) for name, port in re.findall(r"(\w+) (\d+)", line.split(":", 1)[1])}
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _accept(server: socket.socket) -> socket.socket:
    server.settimeout(20)
    conn, _ = server.accept()
    conn.settimeout(10)
    return conn


def _dashboard(host: str, port: int, session: Session) -> None:
    with socket.create_connection((host, port), timeout=10) as sock:
        reader = sock.makefile("rb")
        reader.readline()  # "Connected: Universal Robots Dashboard Server"
        for command in DASHBOARD:
            sock.sendall(command.encode() + b"\n")
            session.dashboard.append((command, reader.readline().decode().strip()))
            time.sleep(0.05)


def _read_primary(sock: socket.socket, session: Session, stop: threading.Event) -> None:
    """The driver's primary client reads the robot state the whole session, as URCL's does."""
    sock.settimeout(0.2)
    while not stop.is_set():
        try:
            chunk = sock.recv(65536)
        except TimeoutError:
            continue
        except OSError:
            return
        if not chunk:
            return
        session.primary += chunk


def run_session(robot_host: str = ROBOT, driver_host: str = DRIVER, ports: Ports | None = None) -> Session:
    """One headless driver session against `rtde-spec serve` (run by this function)."""
    ports = ports or Ports()
    session = Session()
    try:
        _session(robot_host, driver_host, ports, session)
    except (OSError, TimeoutError) as exc:
        time.sleep(0.2)
        said = "\n".join(session.robot_messages())
        raise RuntimeError(
            f"the session failed: {exc}; the robot logged:\n{''.join(session.robot_log)}\nand sent:\n{said}"
        ) from exc
    return session


def _session(robot_host: str, driver_host: str, ports: Ports, session: Session) -> None:
    with contextlib.ExitStack() as stack:
        served = stack.enter_context(robot(robot_host, ports, session.robot_log))
        listeners = {
            name: stack.enter_context(socket.create_server((driver_host, getattr(ports, name))))
            for name in ("reverse", "trajectory", "script_command")
        }
        bound = {name: s.getsockname()[1] for name, s in listeners.items()}
        _dashboard(robot_host, served["dashboard"], session)
        rtde = stack.enter_context(RtdeClient(robot_host, served["rtde"]))
        rtde.setup_outputs(OUTPUTS, RTDE_FREQUENCY)
        speed = rtde.setup_inputs(INPUTS)
        rtde.start()
        rtde.send(speed, speed_slider_mask=1, speed_slider_fraction=1.0)
        stop = threading.Event()
        primary = stack.enter_context(socket.create_connection((robot_host, served["primary"]), timeout=10))
        reader = threading.Thread(target=_read_primary, args=(primary, session, stop), daemon=True)
        reader.start()
        stack.callback(reader.join, 5)
        stack.callback(stop.set)
        primary.sendall(PROGRAM.format(driver=driver_host, **bound).encode())  # headless mode
        # the program connects back in the order it opens its sockets
        reverse = stack.enter_context(_accept(listeners["reverse"]))
        trajectory = stack.enter_context(_accept(listeners["trajectory"]))
        script_command = stack.enter_context(_accept(listeners["script_command"]))
        start = time.monotonic()
        for i in range(SERVO_STEPS + 1):  # a ramp of servoj targets, one per 2 ms control step
            q = tuple(h + 0.1 * math.sin(math.pi / 2 * i / SERVO_STEPS) for h in HOME)
            reverse.sendall(servoj(q))
            session.rtde_rows += _drain(rtde)
            time.sleep(max(0.0, start + (i + 1) * 0.002 - time.monotonic()))
        mass, cog = PAYLOAD
        script_command.sendall(words(1, round(mass * MULT), *scaled(cog), *[0] * 23))  # SET_PAYLOAD
        script_command.sendall(words(0, *[0] * 27))  # ZERO_FTSENSOR
        for point in TRAJECTORY:  # points first, then START on the reverse port, as URCL writes them
            trajectory.sendall(movej_point(*point))
        reverse.sendall(words(200, 1, len(TRAJECTORY), 0, 0, 0, 0, 3))  # FORWARD: TRAJECTORY_START
        trajectory.settimeout(0.02)
        deadline = time.monotonic() + 20
        while session.trajectory_result is None and time.monotonic() < deadline:
            reverse.sendall(words(200, 0, 0, 0, 0, 0, 0, 3))  # FORWARD: NOOP, the driver's keep-alive
            session.rtde_rows += _drain(rtde)
            with contextlib.suppress(TimeoutError):
                reply = trajectory.recv(4)
                if len(reply) == 4:
                    session.trajectory_result = struct.unpack(">i", reply)[0]
        reverse.sendall(words(20, 0, 0, 0, 0, 0, 0, -2))  # STOPPED: the program ends
        reverse.settimeout(10)
        session.program_closed = reverse.recv(64) == b""
        time.sleep(0.3)
        session.rtde_rows += _drain(rtde)
        rtde.pause()


def _drain(rtde: RtdeClient) -> int:
    """Read every data package waiting, as the driver's RTDE thread does each cycle."""
    rows = 0
    with contextlib.suppress(TimeoutError):
        while rtde.receive(timeout=1e-4) is not None:
            rows += 1
    return rows


@contextlib.contextmanager
def dumpcap(path: Path, ports: list[int]) -> Iterator[None]:
    """dumpcap on the loopback interface, every packet to or from these ports, in pcap form."""
    exe = shutil.which("dumpcap")
    if exe is None:
        raise RuntimeError("dumpcap is not installed (Debian package tshark)")
    out = Part(path)  # as every output: beside the name until whole, then renamed (through a symlink)
    part = out.temp
    only = " or ".join(f"tcp port {port}" for port in ports)
    proc = subprocess.Popen([exe, "-q", "-P", "-i", "lo", "-f", only, "-w", str(part)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        try:
            deadline = time.monotonic() + 10
            while not (part.exists() and part.stat().st_size > 0):  # until dumpcap has opened its file
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"dumpcap did not start: {proc.stderr.read() if proc.stderr else ''}")
                time.sleep(0.05)
            time.sleep(0.5)
            yield
            time.sleep(0.5)  # the last segments and FINs
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
            proc.wait(10)
        if proc.returncode not in (0, -signal.SIGTERM):  # it stopped on its own: a full disk, say
            raise RuntimeError(f"dumpcap failed: {proc.stderr.read() if proc.stderr else proc.returncode}")
        out.commit()
    except BaseException:
        out.discard()  # a failed recording leaves nothing behind, and the file that was there as it was
        raise


def _wait_free(host: str, ports: list[int], seconds: float = 600.0) -> None:
    """Until nothing listens on these ports (a test run or another emulator on this machine)."""
    deadline = time.monotonic() + seconds
    while True:
        busy = []
        for port in ports:
            with socket.socket() as sock:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                try:
                    sock.bind((host, port))
                except OSError:
                    busy.append(port)
        if not busy:
            return
        if time.monotonic() > deadline:
            raise RuntimeError(f"{host}: ports {busy} stay in use; stop what listens there")
        time.sleep(1.0)


ATTEMPTS = 20
EXPECTED = ["dashboard", "primary", "rtde", "urcl-reverse", "urcl-script_command", "urcl-trajectory"]


def check(path: Path) -> list[str]:
    """What is wrong with a recorded capture: foreign connections (the ports are the machine's), damage."""
    from rtde_spec.capture.decoder import decode_capture
    from rtde_spec.capture.tables.sink import ArrowSink

    summary = decode_capture(path, ArrowSink())
    kinds = sorted(c.kind for c in summary.connections)
    wrong = [] if kinds == sorted(EXPECTED) else [f"connections {kinds}, not {sorted(EXPECTED)}"]
    return wrong + summary.problems()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "-o", "--output", type=Path, default=SHIPPED, help=f"the capture (default: {SHIPPED})"
    )
    args = parser.parse_args(argv)
    used = Ports()
    robot_ports = [used.dashboard, used.primary, used.secondary, used.realtime, used.rtde]
    driver_ports = [used.reverse, used.trajectory, used.script_command]
    for attempt in range(1, ATTEMPTS + 1):  # the ports are the machine's: others may take them first
        _wait_free(ROBOT, robot_ports + driver_ports)
        try:
            with dumpcap(args.output, [used.dashboard, used.primary, used.rtde, *driver_ports]):
                session = run_session()
            break
        except RuntimeError as exc:
            if attempt == ATTEMPTS or "address already in use" not in str(exc):
                raise
            print(f"attempt {attempt}: a port was taken meanwhile; again", file=sys.stderr)
    wrong = check(args.output)
    print(
        f"wrote {args.output} ({args.output.stat().st_size} bytes): dashboard {len(session.dashboard)} "
        f"commands, {session.rtde_rows} RTDE rows, trajectory result {session.trajectory_result}, "
        f"program {'ended' if session.program_closed else 'still running'}"
    )
    for problem in wrong:
        print(f"error: {problem}; record again", file=sys.stderr)
    return 0 if session.trajectory_result == 0 and session.program_closed and not wrong else 1


if __name__ == "__main__":
    raise SystemExit(main())
