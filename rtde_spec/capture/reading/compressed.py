"""Capture files as users keep them: plain, or compressed whole (`.pcap.gz`, `.pcapng.zst`, ...).

Wireshark reads gzip, zstd and lz4 captures as they are, so users pass them as they are. A file
is opened by what its first bytes are, not by its name: gzip, xz and bzip2 with the standard
library, zstd and lz4 with the `zstandard` and `lz4` packages when installed (else a usage error
naming the file, the package and the command that decompresses it). A compressed stream is read,
not mapped; one that ends early (a download or a copy cut short, a file still being written) or
is corrupt ends the capture there: what came before is decoded, and `stats['compressed_cut']`
(the decompressed bytes read) lets the summary say so.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import IO, Any, cast

from rtde_spec.errors import UsageError

GZIP = b"\x1f\x8b"  # how every gzip member starts
# first bytes -> (name, module, the command that decompresses a file of it)
MAGIC = {
    GZIP: ("gzip", "gzip", "gunzip -k"),
    b"\x28\xb5\x2f\xfd": ("zstd", "zstandard", "zstd -d"),
    b"\x04\x22\x4d\x18": ("lz4", "lz4.frame", "lz4 -d"),
    b"\xfd7zXZ\x00": ("xz", "lzma", "xz -dk"),
    b"BZh": ("bzip2", "bz2", "bunzip2 -k"),
}
SUFFIXES = (".gz", ".zst", ".lz4", ".xz", ".bz2")  # how such files are named (they are opened by their bytes)
CHUNK = 1 << 18  # decompressed a step at a time: a stream cut off loses the step it ends in
PACKAGES = {"zstandard": "zstandard", "lz4.frame": "lz4"}  # module -> what pip installs it as


def open_capture(path: str | Path, stats: dict[str, int]) -> IO[bytes]:
    """The capture file for reading: itself, or its decompressed bytes when it is compressed."""
    f = open(path, "rb")  # closed by the caller, or here on an error
    try:
        head = f.peek(6)[:6] if isinstance(f, io.BufferedReader) else b""
        kind = next((v for magic, v in MAGIC.items() if head.startswith(magic)), None)
        if kind is None:
            return f
        return cast(IO[bytes], Decompressed(_decompressor(f, path, *kind), stats))
    except BaseException:
        f.close()
        raise


def _decompressor(f: IO[bytes], path: str | Path, name: str, module: str, command: str) -> Any:
    import importlib

    try:
        lib = importlib.import_module(module)
    except ImportError:
        package = PACKAGES.get(module, module)
        raise UsageError(
            f"a {name}-compressed capture, and reading {name} needs the Python package {package} "
            f"(pip install {package}); or decompress it first ({command} {path}) and give the result",
            subject=f"file {path}",
        ) from None
    if module == "zstandard":
        try:  # a file of several frames (pzstd, zstd --adapt) reads as one stream
            return lib.ZstdDecompressor().stream_reader(f, closefd=True, read_across_frames=True)
        except TypeError:  # zstandard before 0.16
            return lib.ZstdDecompressor().stream_reader(f, closefd=True)
    if module == "gzip":
        return GzipMembers(f)
    return lib.open(f, "rb")  # lzma, bz2, lz4.frame


class GzipMembers:
    """A gzip file's members one after another, inflated by zlib a megabyte of input at a time.

    The gzip module reads its input 8 kB at a time, in Python: 1.4x the CPU of zlib alone (a
    125 MB capture: 0.92 against 0.64 s). As the gzip module reads them: members concatenated
    (`cat a.gz b.gz`, pigz), zeros after the last one ignored; anything else after a member, or
    a member cut short, raises (what `Decompressed` counts as the stream's end)."""

    STEP = 1 << 20

    def __init__(self, f: IO[bytes]) -> None:
        import zlib

        self.f, self.zlib = f, zlib
        self.inflate = zlib.decompressobj(16 + zlib.MAX_WBITS)  # a gzip header and trailer
        self.pending = b""  # input not yet inflated
        self.fed = False  # the member has had input (an end before its trailer is a cut)

    def read1(self, size: int) -> bytes:
        while True:
            if self.inflate.eof and not self._next_member():
                return b""
            if not self.pending:
                self.pending = self.f.read(self.STEP)
                if not self.pending:
                    if self.fed:
                        raise EOFError("the compressed file ends inside a gzip member")
                    return b""
            self.fed = True
            out = self.inflate.decompress(self.pending, max(1, size))
            # at a member's end the rest is in unused_data (unconsumed_tail may hold it too: 3.11)
            self.pending = self.inflate.unused_data if self.inflate.eof else self.inflate.unconsumed_tail
            if out:
                return out

    read = read1  # `Decompressed` takes pieces: what one step inflates

    def _next_member(self) -> bool:
        """After a member's trailer: whether another member follows (zeros to the end: none)."""
        while True:
            self.pending = self.pending.lstrip(b"\0")
            if len(self.pending) >= 2:  # the magic may be cut by a read: two bytes to look at
                if not self.pending.startswith(GZIP):
                    raise OSError("not a gzip member after the previous one")
                self.fed = False
                self.inflate = self.zlib.decompressobj(16 + self.zlib.MAX_WBITS)
                return True
            more = self.f.read(self.STEP)
            if not more:
                if self.pending:
                    raise OSError("not a gzip member after the previous one")
                return False
            self.pending += more

    def close(self) -> None:
        self.f.close()


class Decompressed(io.RawIOBase):
    """A compressed capture's bytes; no file descriptor (so it is read, never mapped). Reads fill
    what they are asked for (it is no live pipe); a stream that is cut off or corrupt reads as
    ending there, counted in `stats['compressed_cut']`."""

    def __init__(self, inner: Any, stats: dict[str, int]) -> None:
        super().__init__()
        self.inner, self.stats, self.done = inner, stats, 0
        self.piece = getattr(inner, "read1", inner.read)  # what one step decompresses: little lost to damage

    def readable(self) -> bool:
        return True

    def read(self, size: int | None = -1) -> bytes:
        want = -1 if size is None or size < 0 else size
        pieces, held = [], 0
        while "compressed_cut" not in self.stats and (want < 0 or held < want):
            try:
                data: bytes = self.piece(min(CHUNK, want - held) if want >= 0 else CHUNK)
            except Exception:  # EOFError, zlib.error, LZMAError, ZstdError, ...: the stream ends here
                self.stats["compressed_cut"] = self.done
                break
            if not data:
                break
            pieces.append(data)
            held += len(data)
            self.done += len(data)
        return b"".join(pieces)

    read1 = read

    def close(self) -> None:
        try:
            self.inner.close()
        finally:
            super().close()
