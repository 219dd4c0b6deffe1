"""Protocol-1 output data packages with and without the recipe id byte (issue 27, item 6).

UR's guides put the id in every data package; UR's C++ client library reads protocol-1
data packages without it. The spec records both (spec/rtde/packages.yaml
`data_recipe_id`, with sources) and every decoder reads both, told apart by size: the
live client, the stream decoder, the session decoder and the capture decoder.
"""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RecipeCodec, build
from rtde_spec._generated.constants import DATA_WITHOUT_RECIPE_ID
from rtde_spec.capture.decoder import capture_tables
from rtde_spec.errors import DecodeError
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.rtde.client import RtdeClient
from rtde_spec.rtde.data_forms import lacks_recipe_id, sent_without_recipe_id, with_recipe_id
from rtde_spec.rtde.session import SessionDecoder
from rtde_spec.rtde.stream import Package, StreamDecoder

from .capture_files import Conversation, write

NAMES = ["timestamp", "actual_q", "robot_mode"]
TYPES = ["DOUBLE", "VECTOR6D", "INT32"]
CODEC = RecipeCodec.for_names(NAMES, "output")
ROOT = Path(__file__).resolve().parents[1]


def values(i: int) -> dict[str, object]:
    return {"timestamp": i * 0.008, "actual_q": tuple(i + j / 10 for j in range(6)), "robot_mode": 7}


def with_id(i: int) -> bytes:
    """The guides' form: header, recipe id 1, payload."""
    return CODEC.encode_package(values(i), recipe_id=1)


def without_id(i: int) -> bytes:
    """The form UR's C++ client library reads in protocol 1: header, payload."""
    payload = CODEC.encode(values(i))
    return struct.pack(">HB", 3 + len(payload), ord("U")) + payload


# --- the fact, in the spec and in what codegen makes of it ----------------------


def test_the_spec_records_the_fact_with_its_sources() -> None:
    rules = load_spec(ROOT / "spec").packages.data_recipe_id
    optional = [r for r in rules if r.recipe_id == "optional"]
    assert [(r.protocols, r.senders, r.implied) for r in optional] == [([1], ["controller"], 1)]
    sources = " ".join(optional[0].sources)
    assert "RTDE guide" in sources and "Universal_Robots_Client_Library" in sources and "#114" in sources
    assert DATA_WITHOUT_RECIPE_ID == {("controller", 1): 1}
    doc = (ROOT / "docs" / "reference" / "rtde-packages.md").read_text()
    assert "## The recipe id in data packages" in doc and "DataPackage::parseWith" in doc


def test_the_two_forms_differ_by_the_id_byte_only() -> None:
    bare, whole = without_id(3), with_id(3)
    assert len(whole) == len(bare) + 1 == CODEC.package_size
    assert lacks_recipe_id(bare, CODEC.size) and not lacks_recipe_id(whole, CODEC.size)
    assert with_recipe_id(bare, 1) == whole


# --- the session decoder (the capture decoder's and the demo's) -----------------


def protocol_1_session() -> SessionDecoder:
    session = SessionDecoder()  # no version request: protocol 1
    session.feed("client", build("setup_outputs_v1", variable_names=NAMES))
    session.feed("controller", build("setup_outputs_v1_reply", variable_types=TYPES))
    return session


def test_session_decodes_both_forms_in_protocol_1() -> None:
    session = protocol_1_session()
    got_with, got_without = session.feed("controller", with_id(5)), session.feed("controller", without_id(5))
    assert got_with.values == got_without.values and got_with.values is not None
    assert got_with.values["actual_q"] == pytest.approx(values(5)["actual_q"])
    assert got_without.package.recipe_id == 1 and "without its recipe id" in (got_without.note or "")
    assert got_with.note is None


def test_protocol_2_data_packages_always_carry_the_id() -> None:
    session = SessionDecoder()
    session.feed("client", build("request_protocol_version", protocol_version=2))
    session.feed("controller", build("request_protocol_version_reply", accepted=True))
    session.feed("client", build("setup_outputs_v2", output_frequency=125.0, variable_names=NAMES))
    session.feed("controller", build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=TYPES))
    assert session.feed("controller", with_id(1)).values is not None
    short = session.feed("controller", without_id(1))  # the first payload byte read as a recipe id
    assert short.values is None and short.note is not None


def test_client_input_packages_are_never_read_without_their_id() -> None:
    session = protocol_1_session()
    inputs = RecipeCodec.for_names(["speed_slider_fraction"], "input")
    session.feed("client", build("setup_inputs", variable_names=["speed_slider_fraction"]))
    session.feed("controller", build("setup_inputs_reply", input_recipe_id=1, variable_types=["DOUBLE"]))
    payload = inputs.encode({"speed_slider_fraction": 0.5})
    bare = struct.pack(">HB", 3 + len(payload), ord("U")) + payload
    assert session.guide_form("client", bare) is None  # the spec: inputs always carry the id
    assert session.feed("client", inputs.encode_package({"speed_slider_fraction": 0.5}, 1)).values == {
        "speed_slider_fraction": 0.5
    }


# --- the stream decoder ---------------------------------------------------------


def test_stream_decoder_reads_both_forms_in_protocol_1() -> None:
    stream = StreamDecoder(protocol_version=1, codec=CODEC)
    data = without_id(0) + with_id(1) + without_id(2) + with_id(3) + with_id(4)
    items = list(stream.feed(data))
    stream.close()
    rows: list[tuple[float, bool]] = []
    for item in items:
        if isinstance(item, Package):
            assert item.values is not None
            rows.append((item.values["timestamp"], item.without_recipe_id))
        else:  # a batch of back-to-back packages in the guides' form
            rows += [(float(t), False) for t in item.array["timestamp"]]
    assert [round(t / 0.008) for t, _ in rows] == [0, 1, 2, 3, 4]
    assert [bare for _, bare in rows] == [True, False, True, False, False]
    offsets = [item.offset for item in items]
    assert offsets[:2] == [0, len(without_id(0))]  # offsets are the stream's, not the rewritten bytes'


def test_stream_decoder_refuses_the_form_without_id_in_protocol_2() -> None:
    stream = StreamDecoder(protocol_version=2, codec=CODEC, batch=False)
    with pytest.raises(DecodeError, match="shorter than its recipe"):
        list(stream.feed(without_id(0)))


# --- the live client, against a scripted protocol-1 controller on loopback -------


class Protocol1Controller:
    """A loopback peer that answers like a protocol-1 controller and then sends data packages
    in the forms given (True: without the id), some one per send, the rest in one send."""

    def __init__(self, forms: list[bool]) -> None:
        self.forms = forms
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _packages(self, conn: socket.socket) -> Iterator[bytes]:
        buf = b""
        while True:
            while len(buf) < 3 or len(buf) < struct.unpack_from(">H", buf)[0]:
                chunk = conn.recv(4096)
                if not chunk:
                    return
                buf += chunk
            size = struct.unpack_from(">H", buf)[0]
            yield buf[:size]
            buf = buf[size:]

    def _serve(self) -> None:
        conn, _ = self.server.accept()
        with conn:
            for package in self._packages(conn):
                kind = chr(package[2])
                if kind == "V":
                    conn.sendall(build("request_protocol_version_reply", accepted=True))
                elif kind == "v":
                    conn.sendall(build("get_urcontrol_version_reply", major=3, minor=15, bugfix=8, build=1))
                elif kind == "O":
                    conn.sendall(build("setup_outputs_v1_reply", variable_types=TYPES))
                elif kind == "S":
                    conn.sendall(build("start_reply", accepted=True))
                    made = [without_id(i) if bare else with_id(i) for i, bare in enumerate(self.forms)]
                    for package_bytes in made[:4]:
                        conn.sendall(package_bytes)
                    conn.sendall(b"".join(made[4:]))

    def close(self) -> None:
        self.server.close()
        self.thread.join(5)


@pytest.mark.parametrize("forms", [[True] * 12, [False, True] * 6, [False] * 12])
def test_live_client_reads_protocol_1_data_with_and_without_the_id(forms: list[bool]) -> None:
    controller = Protocol1Controller(forms)
    try:
        client = RtdeClient("127.0.0.1", controller.port, timeout=5.0).connect(protocol_version=1)
        try:
            assert client.protocol_version == 1
            client.setup_outputs(NAMES, 125)
            client.start()
            records = [client.receive() for _ in forms]
        finally:
            client.close()
    finally:
        controller.close()
    assert [round(r.timestamp / 0.008) for r in records] == list(range(len(forms)))
    assert records[7].actual_q == pytest.approx(values(7)["actual_q"])
    assert all(r.robot_mode == 7 for r in records)


def test_asyncio_client_reads_protocol_1_data_without_the_id() -> None:
    import asyncio

    from rtde_spec import AsyncRtdeClient

    forms = [True, False] * 5
    controller = Protocol1Controller(forms)

    async def run() -> list[object]:
        client = await AsyncRtdeClient("127.0.0.1", controller.port, timeout=5.0).connect(protocol_version=1)
        try:
            await client.setup_outputs(NAMES, 125)
            await client.start()
            return [await client.receive() for _ in forms]
        finally:
            await client.close()

    try:
        records = asyncio.run(run())
    finally:
        controller.close()
    assert [round(r.timestamp / 0.008) for r in records] == list(range(len(forms)))  # type: ignore[attr-defined]


# --- the capture decoder --------------------------------------------------------


def test_capture_decoder_reads_both_forms_in_protocol_1(tmp_path: Path) -> None:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("get_urcontrol_version"))
    conv.send("server", build("get_urcontrol_version_reply", major=3, minor=15, bugfix=8, build=1))
    conv.send("client", build("setup_outputs_v1", variable_names=NAMES))
    conv.send("server", build("setup_outputs_v1_reply", variable_types=TYPES))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))
    for i in range(20):
        conv.send("server", without_id(i) if i % 3 else with_id(i))
    conv.send("server", b"".join(without_id(i) for i in range(20, 30)))  # ten in one segment
    tables = capture_tables(write(tmp_path / "v1.pcap", [conv]))
    rows = tables["rtde_outputs_1"].to_pylist()
    assert [round(r["timestamp"] / 0.008) for r in rows] == list(range(30))
    assert rows[29]["actual_q_5"] == pytest.approx(29.5)


@pytest.mark.parametrize(
    ("old", "new", "reason"),
    [
        ("  - protocols: [2]\n    senders: [controller]", "  - protocols: [1]\n    senders: [controller]",
         "already has rule"),
        ("    recipe_id: optional\n    implied: 1", "    recipe_id: optional", "implied"),
        ("    sent: without  ", "    ", "sent"),
        ("  - protocols: [2]\n    senders: [controller]", "  - protocols: [3]\n    senders: [controller]",
         "no message is of protocol 3"),
    ],
)  # fmt: skip
def test_a_broken_recipe_id_rule_is_a_spec_error(tmp_path: Path, old: str, new: str, reason: str) -> None:
    import shutil

    from rtde_spec.errors import SpecError

    shutil.copytree(ROOT / "spec", tmp_path / "spec")
    path = tmp_path / "spec" / "rtde" / "packages.yaml"
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(SpecError, match=reason) as info:
        load_spec(tmp_path / "spec")
    assert "packages.yaml" in str(info.value)


# --- the emulator sends what a controller sends -----------------------------------


def _emulator() -> EmulatorThread:
    config = EmulatorConfig(
        host="127.0.0.1", rtde_port=0, primary_port=None, secondary_port=None,
        realtime_port=None, dashboard_port=None,
    )  # fmt: skip
    return EmulatorThread(config)


def _read_package(sock: socket.socket) -> bytes:
    buf = b""
    while len(buf) < 3 or len(buf) < struct.unpack_from(">H", buf)[0]:
        chunk = sock.recv(1)
        assert chunk, "the emulator closed the connection"
        buf += chunk
    return buf


def test_emulator_sends_protocol_1_outputs_without_the_id_as_urbasic_reads_them() -> None:
    """URBasic's session, byte for byte (its RTDE.run: version, protocol 1, names only, start),
    and its reading: the setup reply is the types alone, a data package is the header and the
    variables (RTDE_IO_Config.unpack_recipe, format '>' + the types). With the guides' id byte
    it read every value one byte off: joint positions of 4e+226."""
    names = ["timestamp", "actual_q", "robot_mode"]
    with _emulator() as emu, socket.create_connection(("127.0.0.1", emu.ports["rtde"]), 5) as sock:
        sock.sendall(struct.pack(">HB", 3, ord("v")))
        assert _read_package(sock)[2] == ord("v")
        sock.sendall(struct.pack(">HBH", 5, ord("V"), 1))
        assert _read_package(sock) == struct.pack(">HBB", 4, ord("V"), 1)
        payload = ",".join(names).encode()
        sock.sendall(struct.pack(">HB", 3 + len(payload), ord("O")) + payload)
        reply = _read_package(sock)
        assert reply[3:] == b"DOUBLE,VECTOR6D,INT32"  # no id before the types
        sock.sendall(struct.pack(">HB", 3, ord("S")))
        assert _read_package(sock) == struct.pack(">HBB", 4, ord("S"), 1)
        package = _read_package(sock)
        while package[2] != ord("U"):
            package = _read_package(sock)
    layout = struct.Struct(">d6di")
    assert len(package) == 3 + layout.size  # the header and the variables: no id byte
    timestamp, *q, mode = layout.unpack_from(package, 3)
    assert 0.0 <= timestamp < 60.0
    assert all(-7.0 < v < 7.0 for v in q) and q[1] == pytest.approx(-1.5708, abs=1e-3)
    assert -1 <= mode <= 8


def test_our_clients_read_the_emulator_in_both_protocols() -> None:
    with _emulator() as emu:
        for version in (1, 2):
            client = RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5.0).connect(protocol_version=version)
            with client:
                assert client.protocol_version == version
                client.setup_outputs(["timestamp", "actual_q"], 125)
                client.start()
                records = [client.receive() for _ in range(3)]
            assert records[2].timestamp > records[0].timestamp
            assert records[2].actual_q[1] == pytest.approx(-1.5708, abs=1e-3)


def test_the_spec_says_a_controller_sends_protocol_1_outputs_without_the_id() -> None:
    assert sent_without_recipe_id("controller", 1)
    assert not sent_without_recipe_id("controller", 2) and not sent_without_recipe_id("client", 1)
    rule = next(r for r in load_spec(ROOT / "spec").packages.data_recipe_id if r.recipe_id == "optional")
    assert rule.sent == "without" and any("URBasic" in s for s in rule.sources)
