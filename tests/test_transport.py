"""The transport on real loopback sockets: clients, the emulator, and every error path."""

from __future__ import annotations

import asyncio
import itertools
import re
import socket
import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import AsyncRtdeClient, EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec.emulator.controller.scenario import Scenario
from rtde_spec.errors import EncodeError, RecipeError, RtdeConnectionError, UsageError
from rtde_spec.rtde.codec import build, decode_stream
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

SCENARIO = Scenario.model_validate(
    {
        "controller": "5.15.0",
        "outputs": {
            "actual_q": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            "output_double_register_24": {"ramp": {"start": 1.0, "rate": 2.0}},
        },
    }
)


def emulator(scenario: Scenario = SCENARIO, **ports: int | None) -> EmulatorThread:
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        scenario=scenario,
        realtime_port=None,
        dashboard_port=None,
    )
    for name, port in ports.items():
        setattr(config, name, port)
    return EmulatorThread(config).start()


@pytest.fixture
def emu() -> Iterator[EmulatorThread]:
    running = emulator()
    yield running
    running.stop()


def raw(emu: EmulatorThread) -> socket.socket:
    return socket.create_connection(("127.0.0.1", emu.ports["rtde"]), timeout=2)


def read_packages(sock: socket.socket, count: int) -> list:
    """`count` whole packages from a raw socket, decoded as the controller sent them (protocol 2)."""
    data = b""
    while True:
        try:
            packages = list(decode_stream(data, sender="controller", protocol_version=2))
        except Exception:
            packages = []
        if len(packages) >= count:
            return [m for _, m in packages][:count]
        data += sock.recv(65536)


# --- the handshake, both protocol versions ---------------------------------


@pytest.mark.parametrize("version", [2, 1])
def test_handshake_setup_start_data_and_inputs(emu: EmulatorThread, version: int) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]).connect(protocol_version=version) as client:
        assert client.protocol_version == version
        assert str(client.controller_version) == "5.15.0"
        client.setup_outputs(
            ["timestamp", "actual_q", "input_int_register_24", "actual_digital_output_bits"], 500
        )
        recipe = client.setup_inputs(
            ["input_int_register_24", "standard_digital_output_mask", "standard_digital_output"]
        )
        assert recipe.recipe_id == 1
        client.start()
        first = client.receive()
        assert first.actual_q == (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
        client.send(
            recipe, input_int_register_24=-7, standard_digital_output_mask=0x0F, standard_digital_output=0x05
        )
        deadline = time.time() + 2
        while time.time() < deadline:
            record = client.receive()
            if record.input_int_register_24 == -7:
                break
        assert record.input_int_register_24 == -7
        assert record.actual_digital_output_bits & 0xFF == 0x05
        client.pause()


def test_asyncio_client(emu: EmulatorThread) -> None:
    async def main() -> tuple[object, object]:
        async with AsyncRtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
            await client.setup_outputs(["timestamp", "output_double_register_24"], 250)
            await client.start()
            a = await client.receive()
            b = await client.receive()
            await client.pause()
            return a, b

    a, b = asyncio.run(main())
    assert round(b.timestamp - a.timestamp, 6) == 0.004  # type: ignore[attr-defined]  # 250 Hz of 500
    assert b.output_double_register_24 == pytest.approx(1.0 + 2.0 * b.timestamp)  # type: ignore[attr-defined]


@pytest.mark.skipif(not hasattr(socket, "SO_RCVLOWAT"), reason="no SO_RCVLOWAT on this platform")
def test_batched_reader_wakes_once_per_batch_and_replies_still_come_at_once(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], batch=20) as client:
        client.setup_outputs(["timestamp"], 500)
        reads: list[int] = []
        receive = client.core.receive

        def counted(data: bytes) -> list:
            reads.append(len(data))
            return receive(data)

        client.core.receive = counted  # type: ignore[method-assign]
        client.start()
        stamps = [client.receive().timestamp for _ in range(100)]
        began = time.monotonic()
        client.pause()  # its reply is 4 bytes, far below the low mark: it must not wait for a batch
        answered = time.monotonic() - began
    assert [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * 99  # all, in order
    assert answered < 0.5
    size = client.core.output.package_size
    assert max(reads) >= 20 * size and len(reads) < 100 / 20 * 2 + 4  # a wake-up per ~20 packages


async def _batched_async(port: int) -> tuple[list[float], float]:
    async with AsyncRtdeClient("127.0.0.1", port, batch=20) as client:
        await client.setup_outputs(["timestamp"], 500)
        await client.start()
        stamps = [(await client.receive()).timestamp for _ in range(60)]
        began = time.monotonic()
        await client.pause()
        return stamps, time.monotonic() - began


def test_batched_asyncio_client(emu: EmulatorThread) -> None:
    stamps, answered = asyncio.run(_batched_async(emu.ports["rtde"]))
    assert [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * 59 and answered < 0.5


@pytest.mark.parametrize("batch", [1, 20])
def test_callbacks_take_every_record_instead_of_the_queue(emu: EmulatorThread, batch: int) -> None:
    """Push or pull: with on_data/on_raw every package goes to the callbacks, in order, and
    nothing piles up in a queue nobody reads (so nothing is counted as skipped)."""
    records: list = []
    raws: list[bytes] = []
    with RtdeClient("127.0.0.1", emu.ports["rtde"], queue_size=5, batch=batch) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.on_data(records.append)
        client.on_raw(raws.append)
        client.start()
        deadline = time.monotonic() + 5
        while len(records) < 120 and time.monotonic() < deadline:
            time.sleep(0.01)
        with pytest.raises(UsageError, match="callbacks"):
            client.receive()
        client.pause()
        codec = client.core.output
    assert len(records) >= 120 and client.skipped == 0 and client.received >= len(records)
    stamps = [r.timestamp for r in records[:120]]
    assert [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * 119
    assert records[0].actual_q == pytest.approx((0.1, 0.2, 0.3, 0.4, 0.5, 0.6))
    assert [codec.decode_package(r).timestamp for r in raws[:120]] == stamps  # the same packages


def test_a_client_with_only_raw_callbacks_makes_no_records_until_one_is_wanted(emu: EmulatorThread) -> None:
    """The recorder's case: raw bytes only, so no typed record is made (less CPU per
    package), every package still counted and in order; an `on_data` added later gets records."""
    raws: list[bytes] = []
    records: list = []
    with RtdeClient("127.0.0.1", emu.ports["rtde"], batch=20) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.on_raw(raws.append)
        assert client.core.want_records is False
        client.start()
        deadline = time.monotonic() + 5
        while len(raws) < 100 and time.monotonic() < deadline:
            time.sleep(0.01)
        client.on_data(records.append)
        assert client.core.want_records is True
        while len(records) < 40 and time.monotonic() < deadline:
            time.sleep(0.01)
        client.pause()
        codec = client.core.output
    stamps = [codec.decode_package(r).timestamp for r in raws]
    assert len(stamps) >= 140 and client.received == len(raws) and client.skipped == 0
    assert [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * (len(stamps) - 1)
    assert [r.timestamp for r in records] == stamps[len(stamps) - len(records) :]


def test_recording_reports_nothing_skipped_when_every_row_is_written(
    emu: EmulatorThread, tmp_path: Path
) -> None:
    from rtde_spec.output.writers import open_writer
    from rtde_spec.rtde.recorder import record

    out = tmp_path / "rows.csv"
    writer = open_writer("csv", out)
    with RtdeClient("127.0.0.1", emu.ports["rtde"], queue_size=10) as client:
        result = record(client, ["timestamp"], 500, writer, samples=300)
    writer.close()
    rows = out.read_text().splitlines()[1:]
    assert result.rows == len(rows) == 300 and result.skipped == 0  # more rows than the queue holds


def test_output_rate_is_floor_of_base_over_frequency(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        client.setup_outputs(["timestamp"], 150)  # floor(500 / 150) = 3 steps
        client.start()
        stamps = [client.receive().timestamp for _ in range(5)]
    steps = {round((b - a) * 500) for a, b in itertools.pairwise(stamps)}
    assert steps == {3}


def test_cb3_controller_runs_at_125_hz() -> None:
    cb3 = emulator(Scenario(controller="3.15.8"))
    try:
        with RtdeClient("127.0.0.1", cb3.ports["rtde"]) as client:
            with pytest.raises(RecipeError, match=r"125|frequency"):
                client.setup_outputs(["timestamp"], 500)  # offline: CB3 tops out at 125 Hz
            client.setup_outputs(["timestamp"], 125)
            client.start()
            a, b = client.receive().timestamp, client.receive().timestamp
        assert round((b - a) * 125) == 1
    finally:
        cb3.stop()


# --- what the controller refuses -------------------------------------------


def test_connection_refused_names_host_and_port() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(RtdeConnectionError, match=f"127.0.0.1:{port}"):
        RtdeClient("127.0.0.1", port, timeout=1).connect()


def test_unknown_and_unavailable_names_are_refused_before_sending(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        with pytest.raises(RecipeError, match="actual_qq"):
            client.setup_outputs(["timestamp", "actual_qq"], 125)
        with pytest.raises(RecipeError, match="input"):
            client.setup_outputs(["speed_slider_mask"], 125)  # an input, not an output


def test_what_user_code_passes_to_setup_and_send(emu: EmulatorThread) -> None:
    """Names as one comma string or a generator, values as a pandas row, a dataclass, a record or
    a model: each sent as given. Before, a string was set up a character a name, a generator
    was used up by the offline check (an empty setup, refused by the controller), and send took
    only a mapping (a pandas row raised "truth value ... ambiguous", a model "not a mapping")."""
    import dataclasses

    import numpy as np
    import pandas as pd

    names = ["input_int_register_24", "input_double_register_24"]
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        output = client.setup_outputs("timestamp, input_int_register_24,input_double_register_24", 125)
        assert output.names == ("timestamp", "input_int_register_24", "input_double_register_24")
        recipe = client.setup_inputs(n for n in names)
        assert recipe.names == tuple(names)
        client.start()

        @dataclasses.dataclass
        class Inputs:
            input_int_register_24: int
            input_double_register_24: float

        row = pd.DataFrame({"input_int_register_24": [3], "input_double_register_24": [0.5]}).iloc[0]
        record = recipe.codec.decode_record(recipe.codec.encode({names[0]: 4, names[1]: 1.5}))
        sent = [
            (row, {}, (3, 0.5)),
            (Inputs(5, 2.5), {}, (5, 2.5)),
            (record, {}, (4, 1.5)),
            (recipe.codec.model_type(input_int_register_24=6, input_double_register_24=3.5), {}, (6, 3.5)),
            (row, {"input_int_register_24": np.int64(7)}, (7, 0.5)),  # the names given win
        ]
        for values, named, expected in sent:
            client.send(recipe, values, **named)
            deadline = time.monotonic() + 2
            got = None
            while time.monotonic() < deadline and got != expected:
                got = tuple(getattr(client.receive(), n) for n in names)
            assert got == expected, (values, got)
        with pytest.raises(UsageError, match="send takes the InputRecipe that setup_inputs returned"):
            client.send(output, {"input_int_register_24": 1})  # type: ignore[arg-type]
        with pytest.raises(EncodeError, match="values must be a dict, a record, a model or a dataclass"):
            client.send(recipe, [1, 0.5])
        client.pause()


@pytest.mark.parametrize("frequency", ["125", None, True, b"125"])
def test_a_frequency_that_is_no_number_is_named(emu: EmulatorThread, frequency: object) -> None:
    from rtde_spec.recipes.model import Recipe
    from rtde_spec.recipes.validation import validate_recipes

    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        if frequency is not None:  # None is validate_recipes' "the recipe's own frequency"
            with pytest.raises(UsageError, match="frequency must be a number of Hz"):
                validate_recipes([Recipe(("timestamp",))], frequency=frequency)  # type: ignore[arg-type]
        with pytest.raises(UsageError, match="frequency must be a number of Hz"):
            client.setup_outputs(["timestamp"], frequency)  # type: ignore[arg-type]


def test_recipe_names_that_are_no_names_are_named(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        with pytest.raises(UsageError, match="recipe names must be text: 3 is a int"):
            client.setup_outputs(["timestamp", 3], 125)  # type: ignore[list-item]
        with pytest.raises(UsageError, match="recipe names must be a list of names, not bytes"):
            client.setup_inputs(b"speed_slider_mask")  # type: ignore[arg-type]


def test_emulator_answers_not_found_in_use_and_refuses_start(emu: EmulatorThread) -> None:
    a, b = raw(emu), raw(emu)
    for s in (a, b):
        s.sendall(build("request_protocol_version", protocol_version=2))
    assert read_packages(a, 1)[0].accepted and read_packages(b, 1)[0].accepted
    a.sendall(build("start"))
    reply_and_text = read_packages(a, 2)
    assert {m.NAME for m in reply_and_text} == {"start_reply", "text_message"}
    assert not next(m for m in reply_and_text if m.NAME == "start_reply").accepted
    a.sendall(build("setup_outputs_v2", output_frequency=125.0, variable_names=["timestamp", "no_such"]))
    reply = read_packages(a, 1)[0]
    assert reply.output_recipe_id == 0 and reply.variable_types == ["DOUBLE", "NOT_FOUND"]
    a.sendall(build("setup_inputs", variable_names=["input_int_register_30"]))
    assert read_packages(a, 1)[0].input_recipe_id == 1
    b.sendall(build("setup_inputs", variable_names=["input_int_register_30", "input_int_register_31"]))
    reply = read_packages(b, 1)[0]
    assert reply.input_recipe_id == 0 and reply.variable_types == ["IN_USE", "INT32"]
    a.close()  # the owner leaves: the variable is free again
    time.sleep(0.2)
    b.sendall(build("setup_inputs", variable_names=["input_int_register_30"]))
    assert read_packages(b, 1)[0].variable_types == ["INT32"]
    b.close()


def test_in_use_between_two_clients_through_the_client(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as one, RtdeClient("127.0.0.1", emu.ports["rtde"]) as two:
        one.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])
        with pytest.raises(RecipeError, match="IN_USE"):
            two.setup_inputs(["speed_slider_fraction"])
        one.setup_inputs(["speed_slider_fraction"])  # the same client may use it again


def test_inputs_sent_with_another_clients_recipe_are_refused(emu: EmulatorThread) -> None:
    """client.send(recipe of another client) went out; the controller wrote nothing and said
    "data package of unknown input recipe 1" in a text message the caller never saw."""
    port = emu.ports["rtde"]
    with RtdeClient("127.0.0.1", port, timeout=2) as mine, RtdeClient("127.0.0.1", port, timeout=2) as other:
        theirs = other.setup_inputs(["input_int_register_30"])
        with pytest.raises(UsageError, match="input recipe 1 was set up by another client"):
            mine.send(theirs, input_int_register_30=7)
        other.send(theirs, input_int_register_30=7)


def test_names_over_the_setup_limit_get_a_text_message() -> None:
    """CB3 holds a setup to the CB3 guide's 2048 bytes of names; e-Series takes the 9,173 bytes
    UR's C++ client library sends to current simulators (no limit is documented for it)."""
    names = [f"output_{kind}_register_{i}" for kind in ("double", "int") for i in range(48)]
    assert len(",".join(names)) > 2048
    for controller, refused in (("3.15.8", True), ("5.15.0", False)):
        running = emulator(controller=controller)
        try:
            s = raw(running)
            s.sendall(build("request_protocol_version", protocol_version=2))
            read_packages(s, 1)
            s.sendall(build("setup_outputs_v2", output_frequency=125.0, variable_names=names))
            got = read_packages(s, 2 if refused else 1)
            reply = next(m for m in got if m.NAME == "setup_outputs_v2_reply")
            if refused:
                text = next(m for m in got if m.NAME == "text_message")
                assert "2048" in text.message and reply.output_recipe_id == 0
            else:
                assert reply.output_recipe_id != 0 and len(reply.variable_types) == 96
            s.close()
        finally:
            running.stop()


# --- hostile and broken clients never touch the others ----------------------


def test_garbage_mid_package_disconnects_and_slow_readers(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as good:
        good.setup_outputs(["timestamp"], 500)
        good.start()
        good.receive()
        garbage = raw(emu)
        garbage.sendall(b"\x00\x01\xff" + bytes(range(256)))  # a size below the header: cannot be framed
        assert garbage.recv(4096)  # a text message says why ...
        garbage.settimeout(2)
        while garbage.recv(4096):  # ... then the emulator closes that connection
            pass
        half = raw(emu)
        half.sendall(b"\x00\x10V")  # a package cut in its middle, then gone
        half.close()
        bad_type = raw(emu)
        bad_type.sendall(struct.pack(">HB", 3, ord("Z")))
        assert b"unknown package type" in bad_type.recv(4096)
        bad_type.close()
        before, deadline = good.received, time.monotonic() + 10
        while good.received <= before + 100:  # the well-behaved client keeps getting data at 500 Hz
            assert time.monotonic() < deadline, f"{good.received - before} packages in 10 s"
            time.sleep(0.05)  # (its reader thread keeps off the socket for a lease after receive())


def test_a_slow_consumer_keeps_its_connection(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], queue_size=50) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.start()
        time.sleep(1.0)  # read nothing for a second: 500 packages arrive
        assert client.skipped >= 300  # the oldest were dropped, counted
        newest = client.receive()
        assert client.connection_lost is None
        assert client.receive().timestamp > newest.timestamp


def test_closed_by_the_controller_is_an_error_naming_it() -> None:
    running = emulator()
    client = RtdeClient("127.0.0.1", running.ports["rtde"], timeout=2).connect()
    client.setup_outputs(["timestamp"], 125)
    client.start()
    client.receive()
    running.stop()
    with pytest.raises(RtdeConnectionError, match=r"127\.0\.0\.1"):
        for _ in range(1000):
            client.receive(timeout=2)
    client.close()


def _until_lost(client: RtdeClient | AsyncRtdeClient) -> None:
    deadline = time.monotonic() + 5
    while client.connection_lost is None and time.monotonic() < deadline:
        time.sleep(0.01)


def test_sending_on_an_ended_connection_is_an_error_naming_it() -> None:
    """Inputs sent after the controller closed the connection went to a dead socket without a
    word (blocking client) or raised a bare ConnectionResetError (asyncio); after close(), the
    asyncio client's receive waited its whole time-out. Each now raises RtdeConnectionError."""
    running = emulator()
    client = RtdeClient("127.0.0.1", running.ports["rtde"], timeout=2).connect()
    io = client.setup_inputs(["input_int_register_24"])
    running.stop()
    _until_lost(client)
    with pytest.raises(RtdeConnectionError, match=r"127\.0\.0\.1:\d+: the controller closed"):
        client.send(io, input_int_register_24=1)
    client.close()

    async def asynchronous(running: EmulatorThread) -> None:
        closed = await AsyncRtdeClient("127.0.0.1", running.ports["rtde"], timeout=5).connect()
        await closed.close()
        began = time.monotonic()
        with pytest.raises(RtdeConnectionError, match="closed by this client"):
            await closed.receive()
        assert time.monotonic() - began < 1
        client = await AsyncRtdeClient("127.0.0.1", running.ports["rtde"], timeout=2).connect()
        io = await client.setup_inputs(["input_int_register_24"])
        running.stop()
        for _ in range(500):  # the end comes to the reader task
            if client.connection_lost is not None:
                break
            await asyncio.sleep(0.01)
        for _ in range(3):
            with pytest.raises(RtdeConnectionError, match=r"127\.0\.0\.1"):
                await client.send(io, input_int_register_24=1)
        await client.close()

    asyncio.run(asynchronous(emulator()))


def test_a_failed_handshake_leaves_no_connection_open_and_a_client_connects_once() -> None:
    """A connect() whose handshake failed (no reply, no protocol accepted, not RTDE) left the
    socket open and its reader thread running: `with RtdeClient(...)` never reaches __exit__.
    A closed client's connect() opened a second socket and raised "closed by this client"."""
    with socket.create_server(("127.0.0.1", 0)) as server:  # accepts, never answers
        server.settimeout(5)
        port = server.getsockname()[1]
        with pytest.raises(TimeoutError, match="no reply to request_protocol_version"):
            with RtdeClient("127.0.0.1", port, timeout=0.3):
                pass
        peer, _ = server.accept()
        with peer:
            peer.settimeout(5)
            while peer.recv(4096):  # the request; then the end, not a time-out
                pass
        assert not [t for t in threading.enumerate() if t.name.startswith(f"rtde-reader-127.0.0.1:{port}")]

        async def asynchronous() -> None:
            with pytest.raises(TimeoutError):
                await AsyncRtdeClient("127.0.0.1", port, timeout=0.3).connect()
            peer, _ = server.accept()
            with peer:
                peer.settimeout(5)
                while peer.recv(4096):
                    pass

        asyncio.run(asynchronous())
    running = emulator()
    client = RtdeClient("127.0.0.1", running.ports["rtde"], timeout=2).connect()
    with pytest.raises(UsageError, match="is connected; make a new RtdeClient"):
        client.connect()
    client.close()
    with pytest.raises(UsageError, match="was closed; make a new RtdeClient"):
        client.connect()
    running.stop()


def test_receive_times_out_then_hands_over_what_came_before_a_close() -> None:
    running = emulator()
    client = RtdeClient("127.0.0.1", running.ports["rtde"], timeout=5).connect()
    client.setup_outputs(["timestamp"], 500)
    began = time.monotonic()
    with pytest.raises(TimeoutError, match="no data package"):
        client.receive(timeout=0.2)  # not started: nothing comes
    assert 0.15 < time.monotonic() - began < 2
    client.start()
    time.sleep(0.2)
    running.stop()
    deadline = time.monotonic() + 5
    while client.connection_lost is None and time.monotonic() < deadline:
        time.sleep(0.01)
    stamps = []
    with pytest.raises(RtdeConnectionError):
        while True:
            stamps.append(client.receive().timestamp)  # what came first, then the close
    assert len(stamps) >= 20 and [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * (
        len(stamps) - 1
    )
    client.close()


def test_every_reader_waiting_hears_the_close() -> None:
    running = emulator()
    client = RtdeClient("127.0.0.1", running.ports["rtde"], timeout=10).connect()
    client.setup_outputs(["timestamp"], 125)  # not started: the readers wait
    outcomes: list[str] = []

    def wait() -> None:
        try:
            client.receive()
            outcomes.append("record")
        except RtdeConnectionError:
            outcomes.append("closed")
        except TimeoutError:
            outcomes.append("timeout")

    readers = [threading.Thread(target=wait) for _ in range(3)]
    for r in readers:
        r.start()
    time.sleep(0.2)
    began = time.monotonic()
    running.stop()
    for r in readers:
        r.join(12)
    assert outcomes == ["closed"] * 3 and time.monotonic() - began < 5
    client.close()


# --- several clients, the primary ports, scenarios ---------------------------


def test_several_clients_at_once(emu: EmulatorThread) -> None:
    clients = [RtdeClient("127.0.0.1", emu.ports["rtde"]).connect() for _ in range(4)]
    try:
        for i, c in enumerate(clients):
            c.setup_outputs(["timestamp", "actual_q"], 500 / (i + 1))
            c.start()
        time.sleep(0.5)
        counts = [c.received for c in clients]
        assert all(n > 0 for n in counts) and counts[0] > counts[3] * 2.5
    finally:
        for c in clients:
            c.close()


def test_primary_and_secondary_ports_agree_with_rtde(emu: EmulatorThread) -> None:
    with PrimaryClient("127.0.0.1", emu.ports["secondary"], timeout=2) as client:
        messages = client.messages()
        version = next(messages)
        assert str(client.decoder.version) == "5.15.0" and version.NAME == "version_message"
        state = next(messages)
        assert isinstance(state, RobotStateMessage)
        assert [j.q_actual for j in state["joint_data"].joints] == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
        assert isinstance(state["robot_mode_data"], PrimaryPart) and state["robot_mode_data"].robot_mode == 7
    with PrimaryClient("127.0.0.1", emu.ports["primary"]) as client:
        client.send_script("set_digital_out(1, True)")
        time.sleep(0.2)
    assert any("set_digital_out" in text for _, text in emu.emulator.primary.scripts)


def test_read_only_port_refuses_script_clearly() -> None:
    client = PrimaryClient("127.0.0.1", 30011)
    with pytest.raises(UsageError, match="read-only"):
        client.send_script("popup('hi')")


@pytest.mark.parametrize(
    ("text", "said"),
    [  # each said "outputs.actual_q.bool: Input should be a valid boolean" or named no file
        (
            "outputs:\n  actual_q: {sine: {amplitude: 1, period: 0}}\n",
            "outputs.actual_q.sine.period: Input should be greater than 0",
        ),
        (
            "outputs:\n  actual_q: {ramp: {rate: x}}\n",
            "outputs.actual_q.ramp.rate: Input should be a valid number",
        ),
        ("outputs:\n  robot_mode: hello\n", "outputs.robot_mode: 'hello' is not a number, true or false"),
        ("outputs:\n  actual_q: {sinus: 1}\n", "outputs.actual_q: {'sinus': 1} is not a number"),
        (
            "- controller\n- outputs\n",
            "a scenario is a mapping (controller, outputs, faults, calibrated), not a list",
        ),
    ],
)
def test_a_scenario_error_names_the_key_the_file_got_wrong(tmp_path: Path, text: str, said: str) -> None:
    from rtde_spec.emulator.controller.scenario import load_scenario

    bad = tmp_path / "s.yaml"
    bad.write_text(text)
    with pytest.raises(UsageError) as raised:
        load_scenario(bad)
    assert str(raised.value).startswith(f"scenario file {bad}: {said}"), str(raised.value)


def test_a_scenario_that_is_not_text_is_named(tmp_path: Path) -> None:
    from rtde_spec.emulator.controller.scenario import load_scenario

    bad = tmp_path / "s.yaml"
    bad.write_bytes(b"outputs:\xa0\xff\n")
    with pytest.raises(
        UsageError, match=r"s\.yaml: cannot read scenario: not UTF-8 text: byte 0xa0 at offset 8"
    ):
        load_scenario(bad)


def test_scenario_files_are_validated(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from rtde_spec.emulator.controller.scenario import load_scenario

    bad = tmp_path / "s.yaml"
    bad.write_text("controller: 5.15.0\noutputs:\n  actual_q: {sine: {amplitud: 1}}\n")
    with pytest.raises(UsageError, match=r"scenario file .*actual_q"):
        load_scenario(bad)
    wrong_length = Scenario.model_validate({"outputs": {"actual_q": [1, 2]}})
    from rtde_spec import Catalogue

    with pytest.raises(UsageError, match="actual_q: needs 6 values"):
        wrong_length.functions(Catalogue.builtin())
    unknown = Scenario.model_validate({"outputs": {"actual_qq": 1}})
    with pytest.raises(UsageError, match="unknown output 'actual_qq'"):
        unknown.functions(Catalogue.builtin())


@pytest.mark.parametrize("port", [70000, -1, "30004", 1.5])
def test_a_port_that_is_no_tcp_port_is_refused_before_anything_listens(port: object) -> None:
    """rtde_port=70000 was served on 4464 (70000 - 65536) without a word; "30004" and -1 raised
    socket.gaierror from inside asyncio."""
    config = EmulatorConfig(
        host="127.0.0.26", rtde_port=port, primary_port=None, secondary_port=None,  # type: ignore[arg-type]
        realtime_port=None, dashboard_port=None,
    )  # fmt: skip
    with pytest.raises(UsageError, match=r"rtde_port must be a TCP port 0\.\.65535"):
        with EmulatorThread(config):
            pass


@pytest.mark.parametrize(
    ("options", "said"),
    [
        ({"port": 70000}, "port must be 1..65535, not 70000"),
        ({"port": 0}, "port must be 1..65535, not 0"),
        ({"timeout": None}, "timeout must be a number of seconds above 0, not None"),
        ({"timeout": -1}, "timeout must be a number of seconds above 0, not -1"),
        ({"timeout": "5"}, "timeout must be a number of seconds above 0, not '5'"),
    ],
)
def test_client_options_that_cannot_work_are_named_before_connecting(options: dict, said: str) -> None:
    """Port 70000 connected to port 4464 (70000 - 65536); a timeout of None, -1 or "5" raised
    TypeError or ValueError from inside the socket module, at connect or at the first request."""
    given = {"port": 1, "timeout": 1.0, **options}
    for make in (
        lambda: RtdeClient("127.0.0.1", given["port"], timeout=given["timeout"]).connect(),
        lambda: AsyncRtdeClient("127.0.0.1", given["port"], timeout=given["timeout"]),
        lambda: PrimaryClient("127.0.0.1", given["port"], timeout=given["timeout"]).connect(),
    ):
        with pytest.raises(UsageError, match=re.escape(said)):
            make()


def test_an_emulator_thread_started_twice_serves_once_and_a_stopped_one_says_to_make_a_new_one() -> None:
    """`with emu` after `emu.start()` raised RuntimeError: threads can only be started once; so did
    a start after stop(), naming nothing of ours."""
    config = EmulatorConfig(
        host="127.0.0.28", rtde_port=0, primary_port=0, secondary_port=None, realtime_port=None,
        dashboard_port=None,
    )  # fmt: skip
    emu = EmulatorThread(config).start()
    with emu as same:  # already serving: the same emulator, not a second start
        assert same is emu
        with RtdeClient("127.0.0.28", emu.ports["rtde"]) as client:
            assert client.controller_version
    with pytest.raises(UsageError, match="has stopped; make a new EmulatorThread"):
        emu.start()
