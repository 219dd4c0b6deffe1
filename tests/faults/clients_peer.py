"""A tiny misbehaving RTDE controller on 127.0.0.1 for the client fault tests.

It frames what the client sends by the size field alone and answers each request
through a script the test gives: normal answers by default, a test overrides the
ones it wants wrong (a reply of another type, extra replies, a cut-off package).
"""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Callable

from rtde_spec.rtde.codec import build

HEADER = struct.Struct(">HB")
Answer = Callable[[int, bytes, "HostilePeer"], bytes | None]  # (type letter, package, peer) -> bytes


class HostilePeer:
    """One connection; `answer(type, package, peer)` returns what to send (None: close)."""

    def __init__(self, answer: Answer | None = None, *, accept_versions: tuple[int, ...] = (2,)) -> None:
        self.answer = answer or (lambda kind, package, peer: peer.normal(kind, package))
        self.accept_versions = accept_versions
        self.version = 1
        self.recipe_id = 1
        self.requests: list[str] = []
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.conn: socket.socket | None = None
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def normal(self, kind: int, package: bytes) -> bytes:
        """What a well-behaved controller answers (recipes of DOUBLE fields only)."""
        letter = chr(kind)
        if letter == "V":
            (wanted,) = struct.unpack_from(">H", package, 3)
            accepted = wanted in self.accept_versions
            if accepted:
                self.version = wanted
            return build("request_protocol_version_reply", accepted=accepted)
        if letter == "v":
            return build("get_urcontrol_version_reply", major=5, minor=15, bugfix=0, build=0)
        if letter == "O":
            names = package[3 + (8 if self.version == 2 else 0) :].decode().split(",")
            types = ["DOUBLE"] * len(names)
            if self.version == 1:
                return build("setup_outputs_v1_reply", variable_types=types)
            return build("setup_outputs_v2_reply", output_recipe_id=self.recipe_id, variable_types=types)
        if letter == "S":
            return build("start_reply", accepted=True)
        if letter == "P":
            return build("pause_reply", accepted=True)
        raise AssertionError(f"the peer got an unexpected request {letter!r}")

    def data(self, *values: float) -> bytes:
        """A data package of a one-DOUBLE recipe."""
        return build(
            "data_package", recipe_id=self.recipe_id, payload=b"".join(struct.pack(">d", v) for v in values)
        )

    def send(self, data: bytes) -> None:
        assert self.conn is not None
        self.conn.sendall(data)

    def close(self) -> None:
        if self.conn is not None:
            self.conn.close()
        self.server.close()

    def _serve(self) -> None:
        conn, _ = self.server.accept()
        self.conn = conn
        buf = b""
        try:
            while True:
                chunk = conn.recv(65536)
                if not chunk:
                    return
                buf += chunk
                while len(buf) >= HEADER.size and len(buf) >= HEADER.unpack_from(buf)[0]:
                    size, kind = HEADER.unpack_from(buf)
                    package, buf = buf[:size], buf[size:]
                    self.requests.append(chr(kind))
                    out = self.answer(kind, package, self)
                    if out is None:
                        conn.close()
                        return
                    conn.sendall(out)
        except OSError:
            return
