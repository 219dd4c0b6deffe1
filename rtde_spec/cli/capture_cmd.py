"""rtde-spec capture FILE... -o OUTDIR: pcap/pcapng captures to tables, in parallel over files."""

from __future__ import annotations

import argparse
import glob
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec.cli.arguments import primary_version
from rtde_spec.cli.conventions import dangling_link, describe, file_in_the_way, plural
from rtde_spec.cli.inputs import once_each, piped_in
from rtde_spec.cli.options import add_lenient
from rtde_spec.errors import RtdeSpecError, UsageError
from rtde_spec.printable import safe_text

if TYPE_CHECKING:
    from rtde_spec.capture.decoder import CaptureInterrupted, CapturePath
    from rtde_spec.capture.tables.summary import CaptureSummary

SUFFIXES = (".pcap", ".pcapng", ".cap")
EXIT_MISSING_RECIPE = 1  # data packages that need --recipe (EXIT_ERROR)
EXIT_DAMAGED = 3  # every file read to its end, but some input was damaged and skipped
EPILOG = """\
Output names: each input's files are named STEM-HASH.EXT (and its recipe list
recipes-STEM-HASH.json), HASH being 8 hex digits of the input's absolute path: a/x.pcap
and b/x.pcap never overwrite each other, and re-running on the same file replaces only
that file's outputs. Standard input gets the start time instead of HASH.

Table names: a table of data packages holds one recipe across the whole FOLDER,
rtde_outputs_1 the first met, each other recipe the next free number, in input order
(whatever --jobs is), kept by later runs into FOLDER; recipes-STEM-HASH.json lists each
capture's tables and fields. A FOLDER whose table already mixes recipes is refused.

Damage: a capture is decoded around what is damaged (records cut off, impossible
timestamps, TCP gaps, packages cut or garbled); stderr gets one summary line per file
(frames, packages, gaps, bytes skipped, truncated records) and a line per problem.
Text that is not UTF-8 keeps U+FFFD in its column and the raw bytes in hex in
NAME_raw.

Exit codes: 0 every file decoded whole; 1 data packages need --recipe (or another
error in the data); 2 usage error (no such file, not a capture); 3 decoded, but some
input was damaged or skipped, or nothing was decoded: no UR connection, the TCP
ports seen named (--port-map for moved ones) (0 with --lenient); 130 interrupted
(Ctrl-C, SIGTERM): files finished have their tables whole; a file cut short writes none
and keeps those of an earlier run; a pipe (-) keeps what was decoded."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "capture",
        help="decode pcap/pcapng captures of RTDE and primary/secondary traffic into tables",
        **describe(
            "Decodes pcap/pcapng captures (files, folders, globs or - for a pipe) of RTDE, primary/"
            "secondary, real-time, dashboard and UR ROS driver traffic into one table per kind, written "
            "as a hive-partitioned dataset: "
            "FOLDER/<table>/robot=<address>/date=<day>/<capture>-<hash>.<ext>. "
            "Ports are recognised from the spec or by content (--port-map for moved ones).",
            "rtde-spec capture robot.pcapng -o tables/",
            "rtde-spec capture captures/ -o fleet/ --jobs 2 --format csv",
            "rtde-spec capture late.pcap -o late/ --recipe outputs.txt",
            "tcpdump -w - port 30004 | rtde-spec capture - -o tables/",
        ),
    )
    p.epilog = f"{p.epilog}\n\n{EPILOG}"
    p.add_argument(
        "files",
        nargs="+",
        metavar="FILE",
        help="capture files, folders of them, globs, or - for standard input "
        "(tcpdump -w - ... | rtde-spec capture - -o OUT) (required)",
    )
    p.add_argument(
        "-o", "--output", dest="outdir", required=True, type=output_folder_arg, metavar="FOLDER",
        help="output folder, made when missing (required)",
    )  # fmt: skip
    p.add_argument("--outdir", dest="outdir", type=output_folder_arg, help=argparse.SUPPRESS)  # old -o
    p.add_argument(
        "--format", choices=("parquet", "csv", "jsonl", "mcap"), default="parquet", help="default: parquet"
    )
    p.add_argument(
        "--recipe", metavar="FILE", help="output recipe for captures that start after setup (default: none)"
    )
    p.add_argument(
        "--recipe-key",
        metavar="KEY",
        help="which recipe of a --recipe file with several (default: the only one, else the only "
        "output recipe)",
    )
    p.add_argument(
        "--controller",
        type=primary_version,
        metavar="VERSION",
        help="controller version of primary/secondary connections whose Version message is not in "
        "the capture (one started late), e.g. 1.8 for a CB2: picks the spec's older layouts; a Version "
        "message in the capture wins (default: the newest layouts)",
    )
    _add_port_options(p)
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        metavar="PROCESSES",
        help="files decoded in parallel processes; one file: threads preparing its batches for "
        "the writers while it is read on, the same tables (Parquet; default: 1)",
    )
    add_lenient(p, "exit 0 when an input was damaged (the summary is printed all the same; default: exit 3)")
    p.set_defaults(run=run)


def _add_port_options(p: argparse.ArgumentParser) -> None:
    """Which ports hold which protocol, beyond the spec's defaults and what content tells."""
    p.add_argument(
        "--rtde-port",
        type=int,
        action="append",
        metavar="PORT",
        help=f"RTDE port, repeatable (default: {RTDE_PORT})",
    )
    p.add_argument(
        "--primary-port",
        type=int,
        action="append",
        metavar="PORT",
        help=f"primary/secondary port, repeatable (default: {', '.join(map(str, PRIMARY_PORTS.values()))})",
    )
    p.add_argument(
        "--port-map",
        action="append",
        metavar="PORT=PROTOCOL[,...]",
        help="decode PORT as PROTOCOL (rtde, primary, realtime, dashboard, reverse, script_sender, "
        "trajectory, script_command), repeatable, e.g. 50001=reverse,50003=trajectory (default: the "
        "spec's ports: RTDE 30004, primary 30001/30002/30011/30012, real-time 30003/30013, dashboard "
        "29999, URCL external control 50001-50004)",
    )


def output_folder_arg(text: str) -> str:
    """-o of capture is a folder: an existing file, or a name with a table file's suffix that is
    not a folder yet (-o out.parquet), is refused rather than made into a folder silently."""
    if text == "-":
        raise argparse.ArgumentTypeError("standard output cannot hold a folder of tables; give a folder")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(
            f"{text} is a file, but capture writes a folder (one table per kind); give a folder, e.g. "
            f"{path.stem or 'tables'}/"
        )
    broken = dangling_link(path)
    if broken is not None:
        raise argparse.ArgumentTypeError(f"{text} {broken}")
    in_the_way = file_in_the_way(path)
    if in_the_way is not None:
        raise argparse.ArgumentTypeError(f"{text}: {in_the_way}")
    if not path.exists() and path.suffix.lower() in (".parquet", ".csv", ".jsonl", ".mcap"):
        raise argparse.ArgumentTypeError(
            f"{text} names a file, but capture writes a folder (one table per kind, --format "
            f"{path.suffix[1:].lower()}); give a folder, e.g. {path.stem}/"
        )
    return text


STDIN = "/dev/stdin"  # `-`: a capture piped in (read to its end; Linux and macOS)


def expand(patterns: list[str]) -> list[Path]:
    files: list[Path] = []
    for pattern in patterns:
        if pattern == "-":
            piped_in("a capture", "tcpdump -w - port 30004 | rtde-spec capture - -o tables/", "capture -")
        path = Path(STDIN if pattern == "-" else pattern)
        if path.is_dir():  # .pcap, .pcapng, .cap, tcpdump -C's .pcapN, and those compressed whole
            from rtde_spec.capture.reading.series import capture_files

            files += capture_files(path)
        elif any(ch in pattern for ch in "*?["):  # a pattern the shell left as it was
            for match in sorted(Path(f) for f in glob.glob(pattern, recursive=True)):
                if match.is_dir():  # a folder it matched is searched as a folder given
                    from rtde_spec.capture.reading.series import capture_files

                    files += capture_files(match)
                else:
                    files.append(match)
        elif path.exists():  # a file, or a pipe (read to its end)
            files.append(path)
        else:
            raise UsageError(
                "no such file; give pcap/pcapng files, folders or globs", subject=f"file {pattern}"
            )
    if not files:
        raise UsageError(
            f"no capture files in {', '.join(patterns)} (folders are searched for "
            f"{', '.join(SUFFIXES)}, numbered or compressed; a glob matched nothing)"
        )
    return once_each(files)


def captures_of(files: list[Path]) -> list[CapturePath]:
    """The files as captures: the parts of a split capture given together (a ring buffer,
    `editcap -c`, `tcpdump -C`; `capture/reading/series.py`) are one capture, in their order,
    so a connection that runs on from one part into the next keeps its setup exchange."""
    from rtde_spec.capture.reading.series import group

    return [parts[0] if len(parts) == 1 else parts for parts in group(files)]


def run(args: argparse.Namespace) -> int:
    from rtde_spec.capture.decoder import CaptureInterrupted, decode_to_directory
    from rtde_spec.capture.routing.classify import parse_port_map
    from rtde_spec.cli.record_cmd import names_of

    files = captures_of(expand(args.files))
    options = argparse.Namespace(
        fields=None, recipe=args.recipe, recipe_key=args.recipe_key, extra_fields=args.extra_fields
    )
    recipe = names_of(options, alternative="") if args.recipe else None
    kw: dict[str, Any] = {
        "rtde_ports": tuple(args.rtde_port or (RTDE_PORT,)),
        "primary_ports": tuple(args.primary_port or PRIMARY_PORTS.values()),
        "port_map": parse_port_map(args.port_map or []),
        "controller": args.controller,
    }
    summaries: list[CaptureSummary] = []
    if args.jobs > 1 and len(files) > 1:
        if args.format == "parquet":  # imported once here: forked workers start with it loaded
            import pyarrow.parquet  # noqa: F401

        from rtde_spec.cli.capture_jobs import decode_in_workers

        summaries, stopped = decode_in_workers(files, args.jobs, (args.outdir, args.format, recipe), kw)
        if stopped is not None:
            return _interrupted(summaries, stopped)
    else:
        if args.jobs > 1:  # one file on several cores: framing stays here, batches go to threads
            kw["workers"] = args.jobs - 1
        for f in files:
            bar = _progress(f)
            if bar is not None:
                kw["progress"] = lambda done, bar=bar: bar.update(done - bar.n)
            try:
                summaries.append(decode_to_directory(f, args.outdir, args.format, recipe, **kw))
            except CaptureInterrupted as stop:
                return _interrupted([*summaries, stop.summary] if stop.kept else summaries, [stop])
            finally:
                if bar is not None:
                    bar.close()
    _report(summaries)
    if any(s.needs_recipe() for s in summaries):
        return EXIT_MISSING_RECIPE
    if any(s.damage() or empty(s) for s in summaries) and not args.lenient:
        return EXIT_DAMAGED
    return 0


def _interrupted(finished: list[CaptureSummary], stops: list[CaptureInterrupted]) -> int:
    """Ctrl-C or SIGTERM: what was finished is reported; a file cut short kept its earlier tables."""
    if finished:
        _report(finished, reread=False)
    cut = [stop.summary.file for stop in stops if not stop.kept]
    if cut:
        print(
            safe_text(
                f"interrupted: {', '.join(cut)} not finished, so none of its tables was written "
                "(files of earlier runs are as they were); the tables above are written whole"
            ),
            file=sys.stderr,
        )
    else:
        print("interrupted: the tables above are written whole", file=sys.stderr)
    return 130


def verdict(s: CaptureSummary) -> str:
    """'ok' only when nothing went wrong: else what did (the summary line's second word)."""
    if s.damage():
        return "damaged"
    if s.needs_recipe():
        return "needs --recipe"
    return "nothing decoded" if empty(s) else "ok"


def empty(s: CaptureSummary) -> bool:
    """No rows at all, and not for want of --recipe or for damage (each its own problem)."""
    return not any(s.tables.values()) and not s.needs_recipe() and not s.damage()


def ports_seen(path: str, most: int = 8) -> str:
    """The TCP ports of a capture's connections, most segments first (a file read again)."""
    from collections import Counter

    from rtde_spec.capture.reading.packets import segments

    counts: Counter[int] = Counter()
    try:
        for seg in segments(path):
            counts[min(seg.sport, seg.dport)] += 1  # the lower port: the server's, mostly
    except (OSError, RtdeSpecError):
        return "unknown (the input cannot be read again)"
    if not counts:
        return "none: the capture holds no TCP segments"
    shown = ", ".join(f"{port} ({n} segment{'' if n == 1 else 's'})" for port, n in counts.most_common(most))
    return shown + (f" and {len(counts) - most} more" if len(counts) > most else "")


def nothing_found(s: CaptureSummary, reread: bool = True) -> str:
    """Why a capture gave no rows, naming the ports it holds and --port-map (read again: only a
    regular file, and not after an interrupt)."""
    if s.file == STDIN:
        ports = "unknown (standard input)"
    elif not reread or not Path(s.file).is_file():
        ports = "unknown (not read again)"
    else:
        ports = ports_seen(s.file)
    what = "no RTDE, primary, real-time, dashboard or driver connection" if not s.connections else "no rows"
    return (
        f"{what} found; TCP ports seen: {ports}. If one of them is a UR interface on a moved port, "
        "name it with --port-map PORT=PROTOCOL (e.g. --port-map 8080=rtde)"
    )


def _report(summaries: list[CaptureSummary], reread: bool = True) -> None:
    """stdout: files, connections and tables written; stderr: each file's summary and problems."""
    tables: dict[str, int] = {}
    for s in summaries:
        for name, rows in s.tables.items():
            tables[name] = tables.get(name, 0) + rows
        print(safe_text(f"{s.file}: {plural(s.frames, 'frame')}, {plural(len(s.connections), 'connection')}"))
        for c in s.connections:
            gaps = f", {c.gaps} gaps ({c.lost_bytes} bytes lost)" if c.gaps else ""
            notes = "".join(f"; {note}" for note in c.notes)
            print(safe_text(f"  {c.kind:7s} {c.name}: {plural(c.packages, 'package')}{gaps}{notes}"))
    listed = ", ".join(f"{name} ({plural(rows, 'row')})" for name, rows in sorted(tables.items()))
    print(f"tables: {listed or 'none'}")
    for s in summaries:  # names, notes and problems quote the wire: escaped, never obeyed
        line = s.line()
        if line.startswith(f"{s.file}: ok: "):
            line = f"{s.file}: {verdict(s)}: " + line[len(f"{s.file}: ok: ") :]
        print(safe_text(f"summary {line}"), file=sys.stderr)
        problems = s.problems() + ([nothing_found(s, reread)] if empty(s) else [])
        for problem in distinct(problems):
            print(safe_text(f"  problem: {problem}"), file=sys.stderr)


_WHEN = re.compile(r" at (\d{9,}\.\d{6})(?=:)")  # a problem's capture time: " at 1700000000.002000:"
MAX_PROBLEMS = 20  # distinct problems shown per file; the rest are counted


def distinct(problems: list[str]) -> list[str]:
    """One line per distinct problem: the same problem at many capture times is one line with
    its count and the first and last time; past MAX_PROBLEMS lines, one more counts the rest."""
    groups: dict[str, list[str]] = {}
    for problem in problems:
        groups.setdefault(_WHEN.sub("", problem), []).append(problem)
    lines = []
    for text, same in groups.items():
        if len(same) == 1:
            lines.append(same[0])
            continue
        times = [m.group(1) for p in same if (m := _WHEN.search(p))]
        span = f", at {times[0]} .. {times[-1]}" if times else ""
        lines.append(f"{text} ({len(same)} times{span})")
    if len(lines) > MAX_PROBLEMS:
        rest = sum(len(same) for same in list(groups.values())[MAX_PROBLEMS:])
        more = len(lines) - MAX_PROBLEMS
        lines = [*lines[:MAX_PROBLEMS], f"... and {more} more distinct problems ({rest} in all)"]
    return lines


def _progress(capture: CapturePath):  # type: ignore[no-untyped-def]
    """A progress bar over the capture's bytes (all its parts), on a terminal, for files worth one;
    a compressed file's bar counts the bytes read out of it, with no total to reach."""
    parts = [Path(capture)] if isinstance(capture, (str, Path)) else [Path(p) for p in capture]
    size = sum(p.stat().st_size for p in parts)
    if not sys.stderr.isatty() or size < 8 << 20:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    from rtde_spec.capture.reading.compressed import SUFFIXES

    whole = not any(p.suffix.lower() in SUFFIXES for p in parts)
    return tqdm(
        total=size if whole else None,
        unit="B",
        unit_scale=True,
        desc=parts[0].name,
        file=sys.stderr,
        leave=False,
    )
