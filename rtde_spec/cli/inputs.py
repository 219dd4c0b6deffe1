"""Input bytes as users give them: hex on the command line, a file of hex or binary, or stdin.

A capture file given where packages are expected is named as such, with the command that reads it.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

from rtde_spec.cli.arguments import existing_file
from rtde_spec.cli.hex_dumps import from_hex_forms
from rtde_spec.errors import RtdeSpecError, UsageError
from rtde_spec.printable import safe_text

_HEX_RE = re.compile(r"^[0-9a-fA-F]*$")
_CAPTURE_MAGIC = {
    b"\xa1\xb2\xc3\xd4": "pcap",
    b"\xd4\xc3\xb2\xa1": "pcap",
    b"\xa1\xb2\x3c\x4d": "pcap (nanosecond)",
    b"\x4d\x3c\xb2\xa1": "pcap (nanosecond)",
    b"\x0a\x0d\x0d\x0a": "pcapng",
}


def parse_hex(text: str) -> bytes:
    """Hex with optional spaces, colons, newlines or a 0x prefix."""
    cleaned = re.sub(r"[\s:]", "", text)
    cleaned = cleaned[2:] if cleaned.lower().startswith("0x") else cleaned
    if not _HEX_RE.match(cleaned):
        bad = next(i for i, ch in enumerate(cleaned) if ch not in "0123456789abcdefABCDEF")
        raise RtdeSpecError(f"not hex: character {cleaned[bad]!r} at position {bad}")
    if len(cleaned) % 2:
        raise RtdeSpecError(f"not hex: odd number of digits ({len(cleaned)})")
    return bytes.fromhex(cleaned)


def capture_kind(head: bytes) -> str | None:
    """'pcap' or 'pcapng' when the bytes start like a capture file."""
    return _CAPTURE_MAGIC.get(bytes(head[:4]))


def reject_capture(head: bytes, source: str) -> None:
    kind = capture_kind(head)
    if kind is not None:
        raise UsageError(
            f"this is a {kind} capture file, not RTDE or primary bytes; "
            f"decode it with `rtde-spec capture {source} -o OUTDIR`",
            subject=f"file {source}",
        )


def reject_recording(head: bytes, source: str) -> None:
    """A table file (a recording, `capture`'s output, UR's record.py file) given as packages."""
    from rtde_spec.output.ur_recordings import table_hint

    hint = table_hint(head, source)
    if hint is not None:
        raise UsageError(f"not RTDE or primary bytes: {hint}", subject=f"file {source}")


def not_a_file(arg: str | Path) -> str | None:
    """What `arg` is when it names something that exists but is not a regular file ("a FIFO (named
    pipe)", "a character device", "a directory"); None when it is a file or nothing is there."""
    from rtde_spec.output.partfile import kind_of

    text = str(arg)
    if not text or text == "-" or "\x00" in text:
        return None
    return kind_of(Path(text))


def refuse_special(arg: str | Path, wanted: str, instead: str, option: str = "file") -> None:
    """A usage error when `arg` exists but is no regular file: it says what the path is and why it
    cannot be used (a pipe or device is not read by name: it may wait for a writer, or be empty)."""
    kind = not_a_file(arg)
    if kind is None:
        return
    why = {
        "a directory": "",
        "a FIFO (named pipe)": "; a pipe is read once and waits for a writer, so it is not read by name",
        "a character device": "; a device is not a file of data (/dev/null reads as nothing)",
    }.get(kind, "")
    raise UsageError(f"is {kind}, not {wanted}{why}; {instead}", subject=f"{option} {str(arg)[:200]}")


def read_input(arg: str) -> bytes:
    """HEX_OR_FILE: '-' is stdin, an existing file is read (hex text or binary), else hex."""
    refuse_special(
        arg, "a file of packages", f"give a file, hex, or - with the bytes on standard input (- < {arg[:80]})"
    )
    path = existing_file(arg)
    if arg == "-":
        data = sys.stdin.buffer.read()
    elif path is not None:
        data = path.read_bytes()
    else:
        forms = from_hex_forms(arg)  # a dump line, 0x00,0x05 or \x00\x05
        if forms is not None:
            return forms
        try:
            return parse_hex(arg)
        except RtdeSpecError as exc:
            if os.sep in arg or Path(arg).suffix:
                raise UsageError(
                    "no such file, and not hex either; check the path (or give hex, or - for stdin)",
                    subject=f"file {arg[:80]}",
                ) from None
            raise UsageError(
                f"{arg[:40]!r} is neither a file nor hex ({exc.reason}); give hex (e.g. 00045601), "
                "a file, or - for standard input"
            ) from None
    reject_capture(data, arg)
    if path is not None:
        reject_recording(data[:65536], arg)
    return from_hex_text(data)


def from_hex_text(data: bytes) -> bytes:
    """The bytes that hex text stands for (plain hex, a dump with offsets, a C array, escaped);
    `data` itself when it is not hex text."""
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return data
    forms = from_hex_forms(text)  # first: a dump's offsets are hex digits too
    if forms is not None:
        return forms
    stripped = re.sub(r"[\s:]", "", text)
    if stripped and _HEX_RE.match(stripped) and len(stripped) % 2 == 0:
        return bytes.fromhex(stripped)
    return data


def once_each(files: list[Path]) -> list[Path]:
    """Each file once, where first given: a file given twice (by a folder and a glob, or two
    names of it) would decode into the same tables twice, its rows counted twice."""
    seen: dict[str, Path] = {}
    again: list[Path] = []
    for path in files:
        key = str(path) if str(path) == "/dev/stdin" else os.path.realpath(path)
        if key in seen:
            again.append(path)
        else:
            seen[key] = path
    if again:
        names = ", ".join(safe_text(str(p)) for p in dict.fromkeys(again))
        print(f"note: given more than once, decoded once: {names}", file=sys.stderr)
    return list(seen.values())


def piped_in(what: str, example: str, subject: str) -> None:
    """Refuse standard input that is a terminal: read, it would wait for ever (nobody types `what`)."""
    try:
        terminal = sys.stdin is not None and sys.stdin.isatty()
    except (OSError, ValueError):  # closed
        terminal = False
    if terminal:
        why = f"standard input is a terminal, not {what}: pipe one in ({example})"
        raise UsageError(why, subject=subject)
