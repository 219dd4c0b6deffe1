"""Capture files made by the tests themselves: TCP conversations written frame by frame with dpkt."""

from __future__ import annotations

import socket
import struct
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import dpkt

if TYPE_CHECKING:
    from rtde_spec import RecipeCodec

ACK, FIN, PSH, SYN = dpkt.tcp.TH_ACK, dpkt.tcp.TH_FIN, dpkt.tcp.TH_PUSH, dpkt.tcp.TH_SYN


def _ip(src: str, dst: str, tcp: dpkt.tcp.TCP) -> dpkt.Packet:
    if ":" in src:
        return dpkt.ip6.IP6(
            src=socket.inet_pton(socket.AF_INET6, src), dst=socket.inet_pton(socket.AF_INET6, dst),
            nxt=dpkt.ip.IP_PROTO_TCP, hlim=64, data=tcp, plen=len(bytes(tcp)),
        )  # fmt: skip
    return dpkt.ip.IP(src=socket.inet_aton(src), dst=socket.inet_aton(dst), p=dpkt.ip.IP_PROTO_TCP, data=tcp)


@dataclass
class Conversation:
    """One TCP connection; frames are (time, bytes) as the chosen link type carries them."""

    client: tuple[str, int]
    server: tuple[str, int]
    link: str = "ethernet"  # ethernet | sll | loopback
    time: float = 1_700_000_000.0
    seq: dict[str, int] = field(default_factory=lambda: {"client": 1000, "server": 5000})
    frames: list[tuple[float, bytes]] = field(default_factory=list)
    acking: bool = False  # data segments acknowledge all the other side sent (lost segments too)

    def _frame(self, side: str, seq: int, payload: bytes, flags: int) -> bytes:
        (src, sport), (dst, dport) = (
            (self.client, self.server) if side == "client" else (self.server, self.client)
        )
        ack = self.seq["server" if side == "client" else "client"] if self.acking else 0
        tcp = dpkt.tcp.TCP(sport=sport, dport=dport, seq=seq, ack=ack, flags=flags, data=payload)
        ip = _ip(src, dst, tcp)
        if self.link == "sll":
            proto = dpkt.ethernet.ETH_TYPE_IP6 if ":" in src else dpkt.ethernet.ETH_TYPE_IP
            return bytes(dpkt.sll.SLL(type=0, hrd=772, hlen=6, hdr=b"\0" * 8, ethtype=proto, data=ip))
        if self.link == "loopback":
            family = 30 if ":" in src else 2
            return family.to_bytes(4, "little") + bytes(ip)
        ethtype = dpkt.ethernet.ETH_TYPE_IP6 if ":" in src else dpkt.ethernet.ETH_TYPE_IP
        return bytes(dpkt.ethernet.Ethernet(src=b"\x02" * 6, dst=b"\x04" * 6, type=ethtype, data=ip))

    def handshake(self) -> None:
        self.frames.append((self.time, self._frame("client", self.seq["client"], b"", SYN)))
        self.seq["client"] += 1
        self.frames.append((self.time, self._frame("server", self.seq["server"], b"", SYN | ACK)))
        self.seq["server"] += 1

    def send(self, side: str, data: bytes, dt: float = 0.002, keep: bool = True) -> tuple[int, bytes]:
        """One segment; `keep=False` leaves it out of the capture (a lost segment). Returns it."""
        self.time += dt
        seq = self.seq[side]
        frame = self._frame(side, seq, data, ACK | PSH)
        if keep:
            self.frames.append((self.time, frame))
        self.seq[side] += len(data)
        return seq, frame

    def bare(self, side: str) -> bytes:
        """A segment of `side` without data acknowledging what the other side sent (not added)."""
        frame = dpkt.ethernet.Ethernet(self._frame(side, self.seq[side], b"", ACK))
        tcp = frame.data.data
        tcp.ack, tcp.sum = self.seq["server" if side == "client" else "client"], 0
        frame.data.sum = 0
        return bytes(frame)

    def fin(self, side: str) -> bytes:
        """A FIN of `side` at its next sequence number (not added)."""
        return self._frame(side, self.seq[side], b"", ACK | FIN)

    def resend(self, frame: bytes, dt: float = 0.001) -> None:
        self.time += dt
        self.frames.append((self.time, frame))


def write(path: Path, conversations: list[Conversation], fmt: str = "pcap") -> Path:
    """All conversations' frames, in time order, to a pcap or pcapng file."""
    link = conversations[0].link
    linktype = {
        "ethernet": dpkt.pcap.DLT_EN10MB,
        "sll": dpkt.pcap.DLT_LINUX_SLL,
        "loopback": dpkt.pcap.DLT_NULL,
    }[link]
    frames = sorted((f for c in conversations for f in c.frames), key=lambda f: f[0])
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as out:
        writer = (
            dpkt.pcapng.Writer(out, linktype=linktype)
            if fmt == "pcapng"
            else dpkt.pcap.Writer(out, linktype=linktype)
        )
        for ts, frame in frames:
            writer.writepkt(frame, ts=ts)
    return path


# --- RTDE sessions with losses, for the fault tests and benchmarks/faults_capture.py ---

SMALL = ("timestamp", "actual_q", "robot_mode")  # a 64-byte data package
INPUTS = ("input_int_register_24", "speed_slider_fraction")


def rtde_setup(conv: Conversation, names: tuple[str, ...] = SMALL, recipe_id: int = 1) -> None:
    """Handshake, version, output and input setup, start: what a recorder sends first."""
    from rtde_spec import Catalogue, build

    cat = Catalogue.builtin()
    types = [cat.get(n, "output").type for n in names]  # type: ignore[union-attr]
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=list(names)))
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=recipe_id, variable_types=types))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))


def rtde_packages(count: int, names: tuple[str, ...] = SMALL, recipe_id: int = 1) -> list[bytes]:
    """`count` data packages; `timestamp` is the package's index times 2 ms, floats i + 0.5,
    integers i % 100 (vectors repeat the value)."""
    from rtde_spec import Catalogue, RecipeCodec

    codec = RecipeCodec.for_names(list(names), "output", Catalogue.builtin())
    return [codec.encode_package(package_values(codec, i), recipe_id=recipe_id) for i in range(count)]


def package_values(codec: RecipeCodec, i: int) -> dict[str, object]:
    """Values of package `i`: timestamp i x 2 ms, floats i + 0.5, integers i % 100 (vectors
    repeat the value)."""
    values: dict[str, object] = {}
    for item in codec.items:
        one: object = (i + 0.5) if item.wire.kind == "float" else (i % 100)
        values[item.name] = tuple([one] * item.wire.count) if item.wire.count > 1 else one
    values["timestamp"] = i * 0.002
    return values


def rtde_capture(
    path: Path,
    packages: list[bytes],
    *,
    lost: set[int] = frozenset(),  # type: ignore[assignment]
    segment: int | None = None,
    names: tuple[str, ...] = SMALL,
    fmt: str = "pcap",
) -> Path:
    """An RTDE session: setup, then `packages` from the controller, one per segment or cut
    into `segment`-byte segments; the segments numbered in `lost` are left out."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv, names)
    if segment is None:
        pieces = packages
    else:
        stream = b"".join(packages)
        pieces = [stream[i : i + segment] for i in range(0, len(stream), segment)]
    for n, piece in enumerate(pieces):
        conv.send("server", piece, keep=n not in lost)
    return write(path, [conv], fmt)


def packages_touched(packages: list[bytes], segment: int, lost: set[int]) -> set[int]:
    """Indexes of the packages that share a byte with a lost `segment`-byte segment."""
    touched, start = set(), 0
    for i, package in enumerate(packages):
        end = start + len(package)
        if any(start < (s + 1) * segment and s * segment < end for s in lost):
            touched.add(i)
        start = end
    return touched


def run_capture(*args: str, cwd: Path, stdin: bytes | None = None) -> subprocess.CompletedProcess[str]:
    """`rtde-spec capture ARGS` in a child process, run from `cwd` (not the checkout), so the
    package on PYTHONPATH (or installed) is the one run."""
    done = subprocess.run(
        [sys.executable, "-m", "rtde_spec", "capture", *args],
        capture_output=True,
        cwd=cwd,
        input=stdin,
        timeout=600,
    )
    out, err = (b.decode("utf-8", "replace") for b in (done.stdout, done.stderr))
    return subprocess.CompletedProcess(done.args, done.returncode, out, err)


def pcap_records(path: Path) -> list[tuple[int, int]]:
    """(offset of the record header, captured length) of every record of a classic pcap file."""
    data = path.read_bytes()
    out, pos = [], 24
    while pos + 16 <= len(data):
        (caplen,) = struct.unpack_from("<I", data, pos + 8)
        out.append((pos, caplen))
        pos += 16 + caplen
    return out


# --- the capture fuzz: mutations of frames (TCP, packages) and of the file (pcap/pcapng) ---

ETH_IP_TCP = 14 + 20 + 20  # where a base frame's TCP payload starts (Ethernet, IPv4, TCP, no options)


def _fuzz_strategies():  # type: ignore[no-untyped-def]
    from hypothesis import strategies as st

    index = st.integers(0, 200)
    u32 = st.sampled_from([0, 1, 3, 12, 13, 16, 0xFFFF, 1 << 31, (1 << 32) - 1]) | st.integers(
        0, (1 << 32) - 1
    )
    frame_ops = st.one_of(
        st.tuples(st.just("drop"), index),
        st.tuples(st.just("dup"), index, index),
        st.tuples(st.just("swap"), index, index),
        st.tuples(st.just("seq"), index, st.integers(-5000, 5000)),
        st.tuples(st.just("payload"), index, st.integers(0, 2000), st.integers(0, 255)),
        st.tuples(st.just("size"), index, st.integers(0, 0xFFFF)),  # a package's size field
        st.tuples(st.just("cut"), index, st.integers(0, 120)),  # the frame captured shorter
        st.tuples(st.just("time"), index, st.sampled_from([-1.0, 0.0, 1e12, float(1 << 62)])),
    )
    file_ops = st.one_of(
        st.tuples(st.just("flip"), st.integers(0, 1 << 16), st.integers(0, 255)),
        st.tuples(st.just("truncate"), st.integers(0, 1 << 16)),
        st.tuples(st.just("u32"), st.integers(0, 1 << 16), u32),
        st.tuples(st.just("delete"), st.integers(0, 1 << 16), st.integers(1, 64)),
    )
    return frame_ops, file_ops


FRAME_OPS, FILE_OPS = _fuzz_strategies()


def fuzz_base() -> list[Conversation]:
    """An RTDE session (setup, single, joined and split packages, a text message, client inputs)
    and a primary one (robot state in two segments, a text message with a uint64 of 2^63 and
    text that is not UTF-8, a script)."""
    from rtde_spec import RecipeCodec, build
    from rtde_spec._generated import primary_models as pm
    from rtde_spec.primary.codec import default_codec

    rtde = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(rtde)
    rtde.send("client", build("setup_inputs", variable_names=list(INPUTS)))
    rtde.send("server", build("setup_inputs_reply", input_recipe_id=1, variable_types=["INT32", "DOUBLE"]))
    packages = rtde_packages(40)
    for package in packages[:20]:
        rtde.send("server", package)
    rtde.send("server", b"".join(packages[20:25]))
    rtde.send("server", packages[25][:30])
    rtde.send("server", packages[25][30:] + packages[26][:3])
    rtde.send("server", packages[26][3:])
    rtde.send("server", build("text_message", message="stop", source="Safety", warning_level=1))
    inputs = RecipeCodec.for_names(list(INPUTS), "input")
    rtde.send("client", inputs.encode_package({"input_int_register_24": 5, "speed_slider_fraction": 0.5}, 1))
    for package in packages[27:]:
        rtde.send("server", package)
    primary = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30001))
    primary.handshake()
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    from ur5e_robot_state import ur5e_robot_state_bytes

    state = ur5e_robot_state_bytes()
    for _ in range(3):
        primary.send("server", state[:700], dt=0.05)
        primary.send("server", state[700:], dt=0.0)
    text = pm.TextMessage(timestamp=(1 << 63) + 1, source=-2, robot_message_type=0, text_message="x\udcff")
    primary.send("server", default_codec().encode(text))
    primary.send("client", b"popup(1)\n")
    return [rtde, primary]


def _mutate_frames(conversations: list[Conversation], ops: list[tuple]) -> list[tuple[float, bytes]]:  # type: ignore[type-arg]
    frames = sorted((f for c in conversations for f in c.frames), key=lambda f: f[0])
    for op in ops:
        if not frames:
            break
        name, i = op[0], op[1] % len(frames)
        time, frame = frames[i]
        data = bytearray(frame)
        if name == "drop":
            del frames[i]
            continue
        if name == "dup":
            frames.insert(op[2] % (len(frames) + 1), frames[i])
            continue
        if name == "swap":
            j = op[2] % len(frames)
            frames[i], frames[j] = (frames[j][0], frames[i][1]), (frames[i][0], frames[j][1])
            continue
        if name == "seq" and len(data) >= 42:
            seq = (int.from_bytes(data[38:42], "big") + op[2]) % (1 << 32)
            data[38:42] = seq.to_bytes(4, "big")
        elif name == "payload" and len(data) > ETH_IP_TCP:
            data[ETH_IP_TCP + op[2] % (len(data) - ETH_IP_TCP)] = op[3]
        elif name == "size" and len(data) >= ETH_IP_TCP + 2:
            data[ETH_IP_TCP : ETH_IP_TCP + 2] = op[2].to_bytes(2, "big")
        elif name == "cut":
            del data[op[2] :]
        elif name == "time":
            time = op[2]
        frames[i] = (time, bytes(data))
    return frames


def _mutate_file(data: bytes, ops: list[tuple]) -> bytes:  # type: ignore[type-arg]
    buf = bytearray(data)
    for op in ops:
        if not buf:
            break
        name, pos = op[0], op[1] % len(buf)
        if name == "flip":
            buf[pos] = op[2]
        elif name == "truncate":
            del buf[max(pos, 4) :]
        elif name == "u32":
            buf[pos : pos + 4] = op[2].to_bytes(4, "little")
        elif name == "delete":
            del buf[pos : pos + op[2]]
    return bytes(buf)


def _write_frames(path: Path, frames: list[tuple[float, bytes]], kind: str) -> None:
    """Frames as dpkt writes them; a time dpkt cannot write goes in by struct afterwards."""
    with open(path, "wb") as out:
        writer = (dpkt.pcapng.Writer if kind == "pcapng" else dpkt.pcap.Writer)(
            out, linktype=dpkt.pcap.DLT_EN10MB
        )
        for ts, frame in frames:
            writer.writepkt(frame, ts=ts if 0 <= ts < 1 << 31 else 0.0)


def decode_mutated(
    folder: Path,
    kind: str,
    sink: str,
    frame_ops: list[tuple],
    file_ops: list[tuple],  # type: ignore[type-arg]
) -> str | None:
    """Decode one mutated capture; None, or the foreign exception (not an RtdeSpecError) it raised,
    or what about the outputs cannot be read back."""
    import csv
    import json
    import traceback

    import pyarrow.parquet as pq

    from rtde_spec.capture.decoder import capture_tables, decode_to_directory
    from rtde_spec.errors import RtdeSpecError

    path = folder / f"fuzz.{kind}"
    _write_frames(path, _mutate_frames(fuzz_base(), frame_ops), kind)
    path.write_bytes(_mutate_file(path.read_bytes(), file_ops))
    try:
        if sink == "arrow":
            for table in capture_tables(path).values():
                table.to_pylist()
            return None
        decode_to_directory(path, folder, sink)
    except RtdeSpecError:
        return None
    except Exception:
        return traceback.format_exc()
    try:
        for file in folder.rglob(f"*.{sink}"):
            if sink == "parquet":
                pq.read_table(file)
            elif sink == "jsonl":
                [json.loads(line) for line in file.read_text("utf-8").splitlines()]
            else:
                list(csv.reader(file.open(encoding="utf-8", newline="")))
    except Exception:
        return "unreadable output: " + traceback.format_exc()
    return None


# --- control sessions: outputs and inputs on one connection (ur_rtde's control interface) ---

CONTROL_OUTPUTS = ("timestamp", "actual_q", "robot_mode")
CONTROL_INPUTS = ("input_int_register_24", "input_double_register_24")
COUNT = 400  # packages each way of a control session (control_capture)


def _control_session(
    conv: Conversation, outputs: tuple[str, ...] = CONTROL_OUTPUTS
) -> tuple[RecipeCodec, RecipeCodec]:
    """A control client's setup: outputs (recipe 1) and inputs (recipe 2), then start."""
    from rtde_spec import Catalogue, RecipeCodec, build

    cat = Catalogue.builtin()
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=list(outputs)))
    types = [cat.get(n, "output").type for n in outputs]  # type: ignore[union-attr]
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types))
    conv.send("client", build("setup_inputs", variable_names=list(CONTROL_INPUTS)))
    types = [cat.get(n, "input").type for n in CONTROL_INPUTS]  # type: ignore[union-attr]
    conv.send("server", build("setup_inputs_reply", input_recipe_id=2, variable_types=types))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))
    return RecipeCodec.for_names(list(outputs), "output", cat), RecipeCodec.for_names(
        list(CONTROL_INPUTS), "input", cat
    )


def _output(codec: RecipeCodec, i: int) -> bytes:
    """Package `i` of `codec`'s outputs (`package_values`, robot_mode 7)."""
    values = package_values(codec, i)
    if "robot_mode" in values:
        values["robot_mode"] = 7
    return codec.encode_package(values, recipe_id=1)


def _input(codec: RecipeCodec, i: int) -> bytes:
    return codec.encode_package({"input_int_register_24": i, "input_double_register_24": i / 8}, recipe_id=2)


def _acked(conv: Conversation, side: str) -> None:
    conv.time += 0.0001
    conv.frames.append((conv.time, conv.bare(side)))


def control_capture(
    path: Path,
    *,
    acks: bool = False,
    clients: int = 1,
    between: dict[int, Callable[[Conversation], None]] | None = None,
    count: int = COUNT,
    inputs: bool = True,
    v6: bool = False,
) -> Path:
    """`clients` control sessions, their frames interleaved one by one: each sends an input
    package after every output (and both sides ACK each with `acks`); `between[i]` adds frames
    to the first session after its output number i."""
    host, server = ("fd00::", "fd00::10") if v6 else ("10.0.0.", "10.0.0.10")  # v6: read frame by frame
    convs = [Conversation((f"{host}{2 + n}", 51000 + n), (server, 30004)) for n in range(clients)]
    codecs = [_control_session(conv) for conv in convs]
    for i in range(count):
        for conv, (outputs, writes) in zip(convs, codecs, strict=True):
            conv.time = max(c.time for c in convs) + 0.0001  # one clock: the file keeps this order
            conv.send("server", _output(outputs, i), dt=0.0005)
            if acks:
                _acked(conv, "client")
            if between and i in between and conv is convs[0]:
                between[i](conv)
            if inputs:
                conv.send("client", _input(writes, i), dt=0.0005)
                if acks:
                    _acked(conv, "server")
    return write(path, convs)


# --- the reading with runs against the one that takes each frame alone ---


def same_rows_per_connection(got: dict[str, Any], want: dict[str, Any]) -> None:
    """The same tables, row for row within each connection (runs may deliver one connection's
    rows before another's: their order across connections is not kept)."""
    assert got.keys() == want.keys()
    for name, table in want.items():
        rows, expected = got[name].to_pylist(), table.to_pylist()
        assert len(rows) == len(expected), name
        for conn in {r.get("connection") for r in expected}:
            mine = [r for r in rows if r.get("connection") == conn]
            assert mine == [r for r in expected if r.get("connection") == conn], (name, conn)


def frame_by_frame(patch: Any) -> None:
    """With a monkeypatch: no run found in bulk nor batched, every frame routed and fed alone (the
    reference: each segment's acknowledgment and time seen in its place)."""
    from rtde_spec.capture import runs
    from rtde_spec.capture.reading import bulk

    patch.setattr(bulk, "MIN_RUN", 10**9)
    patch.setattr(runs.Run, "start", classmethod(lambda cls, route, seg: None))


def rtde_raw_setup(rtde: Conversation) -> None:
    """A recorder's setup packed by hand (version 2, timestamp and actual_q at 500 Hz as recipe 1,
    start), as the driver session captures have it."""
    names, types = b"timestamp,actual_q", b"DOUBLE,VECTOR6D"
    rtde.send("client", struct.pack(">HBH", 5, ord("V"), 2))
    rtde.send("server", struct.pack(">HBB", 4, ord("V"), 1))
    rtde.send("client", struct.pack(">HBd", 11 + len(names), ord("O"), 500.0) + names)
    rtde.send("server", struct.pack(">HBB", 4 + len(types), ord("O"), 1) + types)
    rtde.send("client", struct.pack(">HB", 3, ord("S")))
    rtde.send("server", struct.pack(">HBB", 4, ord("S"), 1))
