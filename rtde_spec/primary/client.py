"""A client of the primary/secondary ports: decoded messages in, URScript out where allowed.

Iterating a client yields decoded messages, as the README shows; a message's byte
offset in the socket stream is rarely of use, so it comes only on request:
`client.messages(with_offsets=True)` yields `(offset, message)` pairs, and
`client.last_offset` holds the offset of the message yielded last.
Ports 30011/30012 are read-only: sending URScript there is refused here with a
clear error, instead of the controller silently ignoring it.
"""

from __future__ import annotations

import socket
from collections.abc import Iterator
from typing import Literal, overload

from rtde_spec._generated.constants import PRIMARY_PORTS
from rtde_spec.endpoints import check_endpoint
from rtde_spec.errors import DecodeError, RtdeConnectionError, UsageError
from rtde_spec.primary.codec import PrimaryMessage, PrimaryStreamDecoder

READ_ONLY_PORTS = {port for name, port in PRIMARY_PORTS.items() if name.endswith("read_only")}


class PrimaryClient:
    """`with PrimaryClient(host) as c: for message in c: ...` (decoded messages).

    Port 30001 by default: the primary port sends the robot's messages (errors, texts,
    runtime exceptions) beside Robot State; the secondary 30002 sends only Robot State and
    the Version message."""

    def __init__(self, host: str, port: int = PRIMARY_PORTS["primary"], *, timeout: float = 5.0) -> None:
        self.host, self.port, self.timeout = host, port, timeout
        check_endpoint(host, port, timeout)
        self.decoder = PrimaryStreamDecoder()
        self._sock: socket.socket | None = None
        self.read_only = port in READ_ONLY_PORTS
        self.last_offset: int | None = None  # stream offset of the message yielded last

    @property
    def where(self) -> str:
        return f"{self.host}:{self.port}"

    def connect(self) -> PrimaryClient:
        """A new connection (an earlier one is closed): its stream is framed from its first byte,
        not after what the last connection left half-read."""
        self.close()
        self.decoder, self.last_offset = PrimaryStreamDecoder(), None
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
        except OSError as exc:
            ports = ", ".join(map(str, PRIMARY_PORTS.values()))
            raise RtdeConnectionError(
                f"cannot connect: {exc.strerror or exc}; check the address and that the port is one "
                f"of the primary/secondary ports ({ports}) and reachable",
                subject=self.where,
            ) from None
        return self

    @overload
    def messages(self, with_offsets: Literal[False] = False) -> Iterator[PrimaryMessage]: ...
    @overload
    def messages(self, with_offsets: Literal[True]) -> Iterator[tuple[int, PrimaryMessage]]: ...

    def messages(
        self, with_offsets: bool = False
    ) -> Iterator[PrimaryMessage] | Iterator[tuple[int, PrimaryMessage]]:
        """Decoded messages as they arrive, until the controller closes the connection (a close
        inside a message raises DecodeError saying how much of it came). With `with_offsets`,
        `(offset, message)` pairs: the offset counts bytes of the stream since connecting."""
        pairs = self._pairs()
        return pairs if with_offsets else (message for _, message in pairs)

    def __iter__(self) -> Iterator[PrimaryMessage]:
        return self.messages()

    def _pairs(self) -> Iterator[tuple[int, PrimaryMessage]]:
        if self._sock is None:
            self.connect()
        assert self._sock is not None
        while True:
            try:
                chunk = self._sock.recv(65536)
            except TimeoutError:
                raise TimeoutError(f"nothing from {self.where} within {self.timeout} s") from None
            except OSError as exc:
                self._raise_if_cut(f"connection lost: {exc.strerror or exc}")
                raise RtdeConnectionError(f"connection lost: {exc}", subject=self.where) from None
            if not chunk:
                self._raise_if_cut("the controller closed the connection")
                return
            for offset, message in self.decoder.feed(chunk):
                self.last_offset = offset
                yield offset, message

    def _raise_if_cut(self, cause: str) -> None:
        """A DecodeError if the connection ended inside a message: its bytes are lost, not dropped
        silently."""
        framer = self.decoder.framer
        held = framer.pending
        if not held:
            return
        try:
            framer.close()
        except DecodeError as exc:
            raise DecodeError(
                f"connection closed inside a message: {held} of {exc.expected} ({cause})",
                subject=self.where,
                offset=exc.offset,
                expected=exc.expected,
                actual=exc.actual,
            ) from None

    def send_script(self, script: str) -> None:
        """Send URScript (a program or one line); refused on the read-only ports."""
        if self.read_only:
            raise UsageError(
                "this port is read-only: URScript is accepted on the primary and secondary ports "
                f"({PRIMARY_PORTS['primary']}, {PRIMARY_PORTS['secondary']})",
                subject=self.where,
            )
        if isinstance(script, str):
            script = script.encode("utf-8")  # type: ignore[assignment]
        if not isinstance(script, (bytes, bytearray)):
            raise UsageError(f"URScript is text, not {type(script).__name__}", subject=self.where)
        if self._sock is None:
            self.connect()
        assert self._sock is not None
        try:
            self._sock.sendall(bytes(script) + (b"" if script.endswith(b"\n") else b"\n"))
        except OSError as exc:  # the controller closed the connection, or it was lost
            raise RtdeConnectionError(f"connection lost while sending: {exc}", subject=self.where) from None

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def __enter__(self) -> PrimaryClient:
        return self.connect()

    def __exit__(self, *exc: object) -> None:
        self.close()
