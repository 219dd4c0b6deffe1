"""`watch --foxglove`: a Foxglove WebSocket server with the emulator's live RTDE outputs, primary
messages and the tool frame, read by a plain WebSocket client speaking Foxglove's protocol."""

from __future__ import annotations

import asyncio
import itertools
import json
import math
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import websockets

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.cli.main import main
from rtde_spec.emulator.controller.scenario import Scenario
from rtde_spec.output.foxglove_live import LivePublisher, quaternion

Q = [0.5, -1.2, 1.1, -0.3, 0.4, -0.5]
SCENARIO = Scenario.model_validate({"controller": "5.11.2", "outputs": {"actual_q": Q}})
# the Foxglove SDK's server speaks foxglove.sdk.v1; the Foxglove app offers both names
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA = 0x01  # binary opcode: uint32 subscription id, uint64 log time (both little-endian), payload


@pytest.fixture
def emu() -> Iterator[EmulatorThread]:
    running = EmulatorThread(
        EmulatorConfig(
            rtde_port=0,
            primary_port=0,
            secondary_port=0,
            scenario=SCENARIO,
            realtime_port=None,
            dashboard_port=None,
        )
    ).start()
    yield running
    running.stop()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


Received = dict[str, list[tuple[int, bytes]]]
# foxglove-sdk 0.30.3: a channel created while a client is being connected is advertised to it, but
# subscribing to it is answered "Unknown channel ID"; a new connection has it. So does this client.
UNKNOWN_CHANNEL = "Unknown channel ID"


async def connect(url: str) -> Any:
    deadline = time.monotonic() + 30
    while True:  # the server starts in another thread
        try:
            return await websockets.connect(url, subprotocols=SUBPROTOCOLS)  # type: ignore[arg-type]
        except (OSError, websockets.InvalidHandshake, websockets.InvalidMessage, EOFError):
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.1)


async def listen(
    url: str, enough: Callable[[Received], bool], seconds: float = 60
) -> tuple[dict[str, dict[str, Any]], Received]:
    """Connect, subscribe to every advertised channel, collect messages until `enough` says so,
    the server closes or `seconds` pass: (channels by topic, topic -> [(log time, data)])."""
    channels: dict[str, dict[str, Any]] = {}
    received: Received = {}
    end = time.monotonic() + seconds
    while await _session(await connect(url), channels, received, enough, end):
        pass  # reconnected after an unknown channel
    return channels, received


async def _session(
    ws: Any,
    channels: dict[str, dict[str, Any]],
    received: Received,
    enough: Callable[[Received], bool],
    end: float,
) -> bool:
    """One connection's messages; True if it ended to reconnect."""
    by_subscription: dict[int, str] = {}
    async with ws:
        assert ws.subprotocol in SUBPROTOCOLS
        while time.monotonic() < end and not enough(received):
            try:
                frame = await asyncio.wait_for(ws.recv(), max(0.01, end - time.monotonic()))
            except (asyncio.TimeoutError, websockets.ConnectionClosed):
                return False
            if isinstance(frame, str):
                op = json.loads(frame)
                if op["op"] == "status" and UNKNOWN_CHANNEL in op["message"]:
                    return True
                if op["op"] == "advertise":
                    subscriptions = []
                    for channel in op["channels"]:
                        channels[channel["topic"]] = channel
                        by_subscription[len(by_subscription) + 1] = channel["topic"]
                        subscriptions.append({"id": len(by_subscription), "channelId": channel["id"]})
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
                continue
            opcode, subscription, log_time = struct.unpack_from("<BIQ", frame)
            assert opcode == MESSAGE_DATA
            received.setdefault(by_subscription[subscription], []).append((log_time, bytes(frame[13:])))
    return False


def _varint(buf: bytes, i: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        byte = buf[i]
        value |= (byte & 0x7F) << shift
        i += 1
        if byte < 0x80:
            return value, i
        shift += 7


def protobuf(buf: bytes) -> dict[int, Any]:
    """The fields of a protobuf message by number (enough for foxglove.FrameTransform)."""
    out: dict[int, Any] = {}
    i = 0
    while i < len(buf):
        key, i = _varint(buf, i)
        number, wire = key >> 3, key & 7
        if wire == 0:
            out[number], i = _varint(buf, i)
        elif wire == 1:
            out[number], i = struct.unpack_from("<d", buf, i)[0], i + 8
        elif wire == 2:
            size, i = _varint(buf, i)
            out[number], i = buf[i : i + size], i + size
        else:
            raise AssertionError(f"wire type {wire}")
    return out


def frame_transform(data: bytes) -> dict[str, Any]:
    fields = protobuf(data)
    translation, rotation = protobuf(fields.get(4, b"")), protobuf(fields.get(5, b""))
    return {
        "parent": fields[2].decode(),
        "child": fields[3].decode(),
        "translation": [translation.get(n, 0.0) for n in (1, 2, 3)],
        "rotation": [rotation.get(n, 0.0) for n in (1, 2, 3, 4)],
    }


@pytest.mark.slow  # long end to end: CI runs it (RTDE_SPEC_SLOW=1), the fast loop does not
def test_watch_serves_rtde_outputs_primary_messages_and_the_tool_frame(emu: EmulatorThread) -> None:
    port = free_port()
    argv = ["watch", "--host", "127.0.0.1", "--port", str(emu.ports["secondary"]), "--duration", "8",
            "--foxglove", str(port), "--rtde-port", str(emu.ports["rtde"]),
            "--rtde-frequency", "50"]  # fmt: skip
    codes: list[int] = []
    watcher = threading.Thread(target=lambda: codes.append(main(argv)))
    watcher.start()
    wanted = {"/rtde/outputs/1": 20, "/primary/joint_data": 2, "/primary/robot_mode_data": 2, "/tf": 20}

    def enough(received: Received) -> bool:
        return all(len(received.get(topic, [])) >= count for topic, count in wanted.items())

    channels, received = asyncio.run(listen(f"ws://127.0.0.1:{port}", enough))
    watcher.join(60)  # the watch ends after 8 s (--count counts printed lines: a robot at rest prints 2)
    assert codes == [0] and enough(received), {t: len(m) for t, m in received.items()}
    model = emu.model.values

    rtde = [t for t in received if t.startswith("/rtde/outputs/")]
    assert len(rtde) == 1, sorted(received)
    schema = json.loads(channels[rtde[0]]["schema"])
    assert channels[rtde[0]]["encoding"] == "json" and channels[rtde[0]]["schemaEncoding"] == "jsonschema"
    assert schema["properties"]["actual_q"]["maxItems"] == 6
    rows = [(t, json.loads(d)) for t, d in received[rtde[0]]]
    assert len(rows) >= 20  # 50 Hz for a few seconds
    for _, row in rows:
        assert row["actual_q"] == pytest.approx(Q) and list(model["actual_q"]) == pytest.approx(Q)
        assert row["actual_TCP_pose"] == pytest.approx(list(model["actual_TCP_pose"]))
    stamps = [row["timestamp"] for _, row in rows]
    assert all(b > a for a, b in itertools.pairwise(stamps))
    times = [t for t, _ in rows]  # log times: the controller's spacing, in ns
    for (t0, r0), (t1, r1) in itertools.pairwise(rows):
        assert t1 - t0 == pytest.approx((r1["timestamp"] - r0["timestamp"]) * 1e9, abs=2)
    assert abs(times[0] - time.time_ns()) < 60e9

    joints = [json.loads(d) for _, d in received["/primary/joint_data"]]
    assert joints and [j["q_actual"] for j in joints[-1]["joints"]] == pytest.approx(Q)
    modes = [json.loads(d) for _, d in received["/primary/robot_mode_data"]]
    assert modes and modes[-1]["robot_mode"] == 7 and "offset" not in modes[-1]  # RUNNING

    assert channels["/tf"]["schemaName"] == "foxglove.FrameTransform"
    frames = [frame_transform(d) for _, d in received["/tf"]]
    pose = list(model["actual_TCP_pose"])
    assert frames and all((f["parent"], f["child"]) == ("base", "tool") for f in frames)
    assert frames[-1]["translation"] == pytest.approx(pose[:3])
    assert frames[-1]["rotation"] == pytest.approx(list(quaternion(*pose[3:])))


def test_publisher_on_any_free_port_sends_rows_to_a_subscriber() -> None:
    with LivePublisher(port=0) as live:
        assert live.port > 0 and live.url == f"ws://127.0.0.1:{live.port}"
        stop = threading.Event()

        def feed() -> None:
            i = 0
            while not stop.is_set():
                live.publish_row({"package": "text_message", "package_type": "M", "message": f"m{i}"})
                i += 1
                time.sleep(0.02)

        feeder = threading.Thread(target=feed)
        feeder.start()
        try:
            channels, received = asyncio.run(
                listen(live.url, lambda r: len(r.get("/rtde/text_message", [])) >= 5)
            )
        finally:
            stop.set()
            feeder.join()
    texts = [json.loads(d)["message"] for _, d in received["/rtde/text_message"]]
    assert len(texts) >= 5 and texts == [f"m{int(t[1:])}" for t in texts]
    numbers = [int(t[1:]) for t in texts]
    assert (
        numbers == sorted(numbers)
        and json.loads(channels["/rtde/text_message"]["schema"])["type"] == "object"
    )


def test_rotation_vectors_become_unit_quaternions() -> None:
    assert quaternion(0, 0, 0) == (0.0, 0.0, 0.0, 1.0)
    x, y, z, w = quaternion(0, 0, math.pi / 2)
    assert (x, y) == (0, 0) and z == pytest.approx(math.sqrt(0.5)) and w == pytest.approx(math.sqrt(0.5))
    q = quaternion(0.3, -1.2, 2.0)
    assert math.fsum(v * v for v in q) == pytest.approx(1.0)


def test_a_port_out_of_range_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["watch", "--host", "127.0.0.1", "--foxglove", "70000"]) == 2
    assert "--foxglove 70000" in capsys.readouterr().err


def test_the_live_view_serve_runs_against_its_own_ports(emu: EmulatorThread) -> None:
    """LiveView, what `serve --foxglove` starts beside the emulator: RTDE outputs and the secondary
    port's Robot State reach a subscriber; stopping it closes the server."""
    import argparse

    from rtde_spec.cli.live_view import LiveView, add_live_arguments

    parser = argparse.ArgumentParser()
    add_live_arguments(parser, rtde_port=False)  # serve has its own --rtde-port: the emulator's
    args = parser.parse_args(
        ["--foxglove", "0", "--rtde-fields", "timestamp,actual_q", "--rtde-frequency", "25"]
    )
    view = LiveView("127.0.0.1", emu.ports["rtde"], emu.ports["secondary"], args).start()
    assert view.live is not None
    url = view.live.url
    try:
        wanted = {"/rtde/outputs/1": 5, "/primary/joint_data": 2}
        _, received = asyncio.run(
            listen(url, lambda r: all(len(r.get(t, [])) >= n for t, n in wanted.items()))
        )
    finally:
        view.stop()
    rows = [json.loads(d) for _, d in received["/rtde/outputs/1"]]
    assert set(rows[0]) == {"recipe_id", "timestamp", "actual_q"} and rows[-1]["actual_q"] == pytest.approx(Q)
    joints = json.loads(received["/primary/joint_data"][-1][1])["joints"]
    assert [j["q_actual"] for j in joints] == pytest.approx(Q)
    # the server is gone: refused, or (a parallel test may take the freed port) no Foxglove handshake
    with pytest.raises((OSError, websockets.exceptions.InvalidHandshake)):
        asyncio.run(asyncio.wait_for(websockets.connect(url, subprotocols=SUBPROTOCOLS), 5))  # type: ignore[arg-type]


def test_serve_with_foxglove_publishes_the_emulator_live() -> None:
    """`rtde-spec serve --foxglove PORT` as a user starts it: the emulator's joints reach a subscriber."""
    import subprocess
    import sys

    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "serve", "--rtde-port", "0", "--primary-port", "0",
         "--secondary-port", "0", "--dashboard-port", "0", "--realtime-port", "0", "--foxglove", str(port),
         "--rtde-fields", "timestamp,actual_q", "--rtde-frequency", "25"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        _, received = asyncio.run(
            listen(f"ws://127.0.0.1:{port}", lambda r: len(r.get("/rtde/outputs/1", [])) >= 3)
        )
    finally:
        proc.terminate()
        proc.wait(20)
    rows = [json.loads(d) for _, d in received["/rtde/outputs/1"]]
    assert len(rows[-1]["actual_q"]) == 6 and rows[-1]["timestamp"] > rows[0]["timestamp"]
