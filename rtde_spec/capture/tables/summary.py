"""What a capture gave and what it lost, per file and per connection: the summary `capture` prints.

Damage is anything the input lacked or garbled: records cut off or unreadable,
frames cut by a snap length, frames whose headers or link type cannot be read,
impossible timestamps, TCP gaps, bytes passed over to find the next package, packages
cut by a gap or by the end of the capture, packages that do not decode. A capture
that starts in the middle of a connection is not damaged: the bytes before its first
package boundary are counted apart (`lead_in`). Packages without a known recipe are
not damage either: the user can decode them by giving `--recipe`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path


@dataclass
class ConnectionSummary:
    name: str
    kind: str
    packages: int
    gaps: int
    lost_bytes: int  # in TCP gaps: never in the capture
    errors: list[str]
    unknown_recipe_sizes: dict[int, int]
    skipped_bytes: int = 0  # in the capture, but passed over to find the next package
    cut_packages: int = 0  # begun before a gap and never completed (the end of the capture: in errors)
    lead_in_bytes: int = 0  # before the first package of a connection captured from its middle
    notes: list[str] = field(default_factory=list)  # choices made decoding it (a URCL layout), not damage
    conflicts: int = 0  # retransmissions whose bytes differ from the copy decoded
    conflict_bytes: int = 0
    folded: int = 0  # how many connections this line stands for, past the ones listed (0: itself)


@dataclass
class CaptureSummary:
    file: str
    frames: int = 0
    connections: list[ConnectionSummary] = field(default_factory=list)
    tables: dict[str, int] = field(default_factory=dict)
    paths: list[str] = field(default_factory=list)
    reading: dict[str, int] = field(default_factory=dict)  # the file reader's counts (pcapfile, packets)

    @property
    def packages(self) -> int:
        return sum(c.packages for c in self.connections)

    def cut_by_snap_length(self) -> str | None:
        """Why frames hold less than they had, when they do: the capture's snap length (or another
        cut). First among the problems: the TCP gaps, cut packages and missing setup it causes
        are its consequences, and capturing again with -s 0 is the remedy."""
        r = self.reading
        cut = r.get("cut_frames", 0)
        if not cut:
            return None
        low, high, snap = r.get("cut_at_min", 0), r.get("cut_at_max", 0), r.get("snaplen", 0)
        frames = f"{cut} frame{'' if cut == 1 else 's'}"
        if low == high == snap:
            how = f"{frames} cut at {snap} bytes by the capture's snap length"
        else:
            kept = f"{low}" if low == high else f"{low} to {high}"
            how = f"{frames} captured shorter than they were ({kept} bytes of each kept)"
        return (
            f"{how}{self._cut_when()}: the rest of their TCP payload is not in the file (the gaps and cut "
            "packages below); capture with -s 0 (tcpdump, dumpcap, tshark) to keep whole frames"
        )

    def _cut_when(self) -> str:
        """Where in the capture the cut frames are: the capture times of the first and last."""
        r = self.reading
        if "cut_first_us" not in r:
            return ""
        first, last = (_utc(r[key] / 1e6) for key in ("cut_first_us", "cut_last_us"))
        return f", the first at {first}" + ("" if last == first else f", the last at {last}")

    def damage(self) -> list[str]:
        """What was lost or garbled, one line each; empty for an undamaged input."""
        out = []
        r = self.reading
        cut = self.cut_by_snap_length()
        if cut:
            out.append(cut)
        out += self._ends()
        if r.get("bad_records"):
            out.append(
                f"{r['bad_records']} records whose length cannot be one: "
                f"{r.get('skipped_file_bytes', 0)} bytes skipped to the next whole record"
            )
        if r.get("empty_records"):
            out.append(
                f"{r['empty_records']} records that hold no frame (skipped): a stretch of zeros, as a "
                "preallocated or unfinished capture file ends, reads as such records"
            )
        if r.get("bad_times"):
            out.append(f"{r['bad_times']} frames with an impossible capture time (kept; date=unknown)")
        if r.get("undecodable"):
            out.append(f"{r['undecodable']} frames whose IP/TCP headers do not decode (skipped){self._why()}")
        if r.get("unknown_link"):
            link = r.get("unknown_link_type", -1)
            kind = "of an interface the file never describes" if link < 0 else f"of link type {link}"
            out.append(
                f"{r['unknown_link']} frames {kind}, which this reader does not decode (skipped; it reads "
                "Ethernet, Linux cooked SLL/SLL2, BSD loopback, raw IP, Linux NFLOG and Apple's PKTAP)"
            )
        if r.get("tunnel_cut"):
            out.append(
                f"{r['tunnel_cut']} packets carried in tunnels hold less than their IP length says (the "
                "mirror cut them: an ERSPAN session's MTU or truncation): the rest of their TCP payload is "
                "not in the file (the gaps below); mirror whole frames to keep it"
            )
        if r.get("ip_fragments_lost"):
            out.append(
                f"{r['ip_fragments_lost']} IP fragments of datagrams whose other fragments never came "
                "(skipped)" + _expired(r.get("ip_fragments_expired", 0))
            )
        for c in self.connections:
            if c.gaps:
                out.append(f"{c.name}: {c.gaps} TCP gaps, {c.lost_bytes} bytes never captured")
            if c.skipped_bytes or c.cut_packages:
                out.append(
                    f"{c.name}: {c.skipped_bytes} bytes skipped to find the next package "
                    f"({c.cut_packages} packages cut)"
                )
            if c.conflicts:
                out.append(
                    f"{c.name}: {c.conflicts} retransmissions with other bytes than the first copy "
                    f"({c.conflict_bytes} bytes; the first copy was decoded)"
                )
            out += [f"{c.name}: {e}" for e in c.errors]
        if cut:  # the setup exchange may be in the frames cut: no reason to think it was not captured
            out += self._without_recipe(
                "its setup exchange may be in the cut frames: capture with -s 0, or "
                "give the recipe with --recipe FILE"
            )
        return out

    def _why(self) -> str:
        """What was wrong with the unreadable frames, per reason: how many, and the first's number."""
        r = self.reading
        reasons = [key[4:] for key in r if key.startswith("why:")]
        if not reasons:
            return ""
        parts = []
        for why in reasons:
            first = r.get("first:" + why)
            where = f"frame {first}" if r["why:" + why] == 1 else f"the first is frame {first}"
            parts.append(f"{r['why:' + why]}: {why}" + (f" ({where})" if first else ""))
        others = r.get("undecodable", 0) - sum(r["why:" + why] for why in reasons)
        if others > 0:  # past the reasons kept apart
            parts.append(f"{others}: other reasons")
        return ": " + "; ".join(parts)

    def _ends(self) -> list[str]:
        """Where reading the file ended before its end: a record cut off, a file that grew while it
        was read, a compressed stream cut short."""
        out = []
        r = self.reading
        if r.get("truncated"):
            where = f" at byte {r['stopped_at']}" if "stopped_at" in r else ""
            claim = f" (it claims {r['claimed']} bytes)" if r.get("claimed") else ""
            unread = f"; {r['unread_bytes']} bytes not read" if r.get("unread_bytes") else ""
            out.append(f"the last record is cut off{where}{claim}{unread}")
        if r.get("grew_bytes"):
            out.append(
                f"the file grew by {r['grew_bytes']} bytes while it was read (a capture still being "
                "written): it was decoded as it was when opened; decode it again when the capture ends"
            )
        if "compressed_cut" in r:
            out.append(
                f"the compressed file ends early or is corrupt after {r['compressed_cut']} decompressed "
                "bytes: what came before is decoded, the rest cannot be read"
            )
        return out

    def needs_recipe(self) -> list[str]:
        """Data packages that need `--recipe` to decode (a capture that starts after setup).

        Not when frames were cut by a snap length: then that is the cause (in `damage`)."""
        if self.reading.get("cut_frames"):
            return []
        late = "the capture starts after the setup exchange: give the recipe with --recipe FILE"
        return self._without_recipe(self.split_part or late)

    @cached_property
    def split_part(self) -> str | None:
        """Why a part of a split capture (a ring buffer, `editcap -c`) decoded alone has data
        packages without their recipe, and how to decode the parts as one; None otherwise."""
        from rtde_spec.capture.reading.series import earlier, parts_of

        if not any(c.unknown_recipe_sizes for c in self.connections):
            return None
        try:
            before = earlier(self.file) if Path(self.file).is_file() else []
        except OSError:  # the folder cannot be listed
            before = []
        part = parts_of(self.file)
        if not before or part is None:
            return None
        name = Path(self.file).name
        shown = [p.name for p in before[:2]] + (["..."] if len(before) > 2 else [])
        listed = [str(before[0]), *(["..."] if len(before) > 1 else []), self.file]
        parts = part.series if part.in_order else " ".join(listed)
        return (
            f"{name} is a part of a split capture (dumpcap -b, editcap -c, tcpdump -C): its setup "
            f"exchange is in an earlier part ({', '.join(shown)}); decode the parts as one capture: "
            f"mergecap -a -w whole.pcapng {parts} (the parts in order), then rtde-spec capture "
            "whole.pcapng; or give the recipe with --recipe FILE"
        )

    def _without_recipe(self, why: str) -> list[str]:
        out = []
        for c in self.connections:
            if c.unknown_recipe_sizes:
                sizes = ", ".join(
                    f"{n} of {size} bytes" for size, n in sorted(c.unknown_recipe_sizes.items())
                )
                out.append(f"{c.name}: data packages without a recipe ({sizes}); {why}")
        return out

    def problems(self) -> list[str]:
        return self.needs_recipe() + self.damage()

    def notes(self) -> list[str]:
        """The connections' notes, one line each: a note several connections share is counted."""
        named: dict[str, list[str]] = {}
        for c in self.connections:
            for note in c.notes:
                named.setdefault(note, []).append(c.name)
        return [f"{names[0]}: {note}" if len(names) == 1 else f"{note} ({len(names)} connections)"
                for note, names in named.items()]  # fmt: skip

    def line(self) -> str:
        """One line: frames, packages, gaps, bytes skipped, records cut off; then the notes."""
        gaps = sum(c.gaps for c in self.connections)
        lost = sum(c.lost_bytes for c in self.connections)
        skipped = sum(c.skipped_bytes for c in self.connections)
        truncated = self.reading.get("truncated", 0) + self.reading.get("bad_records", 0)
        verdict = "damaged" if self.damage() else "ok"
        notes = "".join(f"; {note}" for note in self.notes())
        return (
            f"{self.file}: {verdict}: {self.frames} frames, {self.packages} packages, {gaps} gaps "
            f"({lost} bytes lost), {skipped} bytes skipped, {truncated} truncated records{notes}"
        )


def _expired(datagrams: int) -> str:
    if not datagrams:
        return ""
    return (
        f"; {datagrams} of those datagrams waited past the reassembly time-out (30 s for IPv4, 60 s "
        "for IPv6, as Linux holds them): a later datagram of the same id is not mixed with them"
    )


def _utc(seconds: float) -> str:
    """A capture time as UTC with microseconds, as Wireshark's "UTC date and time" shows it."""
    import time

    try:
        whole, micros = divmod(round(seconds * 1e6), 1_000_000)
        return time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(whole)) + f".{micros:06d} UTC"
    except (OverflowError, OSError, ValueError):
        return f"{seconds:.6f} s"
