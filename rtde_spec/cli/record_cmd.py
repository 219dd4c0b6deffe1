"""rtde-spec record: a controller's outputs to CSV or Parquet, as UR's recorder names the columns."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from rtde_spec._generated.constants import RTDE_PORT
from rtde_spec.cli.arguments import RECIPE_FILE_HELP, existing_file
from rtde_spec.cli.conventions import describe, output_file, plural
from rtde_spec.cli.options import add_connection
from rtde_spec.errors import RtdeSpecError, UsageError
from rtde_spec.printable import safe_text

if TYPE_CHECKING:
    from rtde_spec.output.base import Writer
    from rtde_spec.rtde.client import RtdeClient

DESCRIPTION = """\
How a recording ends:
  Ctrl-C, SIGTERM (timeout, kill, systemd) and SIGHUP (a closed terminal) stop it
  cleanly: every row received is written, the file is closed readable, exit code 0
  as for --duration. A second signal stops at once (a CSV or JSON Lines file keeps
  the batches written; a Parquet file not yet closed is lost). A dropped connection
  keeps every row received and exits 1.

Nothing lost:
  -o is written beside its name (.NAME.part-PID) and replaces an existing file only
  once rows arrive: a run that fails first (a refused recipe or --frequency, no
  connection) leaves it byte-identical and no temporary file behind.
  CSV, JSON Lines and MCAP are in place from the first batch on and handed to the
  operating system every batch (0.2 s): a killed recorder (SIGKILL) loses at most
  the last batch, every line (MCAP: every chunk) complete; MCAP readers read such a
  file in order without its summary (`mcap recover` adds it). (The trade-off: a reader may see the file
  grow, batch by batch, as with any log; all of it is always whole lines.)
  Parquet needs its footer, written at close: until then the file is the hidden
  .NAME.part-PID, which a kill leaves unreadable. Use --split to close parts as you
  go. `record` names files a killed run left when it next starts.
  Every closed file is synced to disk before it is renamed into place, so a power
  loss costs at most the open part.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "record",
        help="record outputs from a controller (or the emulator) to CSV/Parquet/JSON Lines",
        **describe(
            "Records a controller's outputs over RTDE to CSV, Parquet, JSON Lines or MCAP (-o, the format "
            "from its suffix), columns named as UR's recorder names them (vectors as name_0..name_5), "
            "until --duration, --samples or Ctrl-C. Nothing is lost: see 'How a recording ends' below.",
            "rtde-spec record --host 127.0.0.1 --fields timestamp,actual_q --duration 2 -o run.parquet",
            "rtde-spec record --host 127.0.0.1 --recipe rtde_config.xml --samples 100 -o run.csv",
            "rtde-spec record --host 127.0.0.1 --recipe outputs.txt --split 10min -o parts.parquet",
        ),
    )
    p.epilog = f"{p.epilog}\n\n{DESCRIPTION}"
    add_connection(p, RTDE_PORT, "RTDE port", "seconds to wait for replies")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument(
        "--recipe",
        "--config",
        metavar="FILE",
        help=f"{RECIPE_FILE_HELP}; --config as UR's record.py names it (required: this or --fields)",
    )
    what.add_argument(
        "--fields",
        action="append",
        metavar="A,B,...",
        help="output names, comma-separated, or the option given again (required: this or --recipe)",
    )
    p.add_argument(
        "--recipe-key",
        metavar="KEY",
        help="which recipe of a file with several (UR's record.py: --recipe-key out) (default: the only "
        "recipe, else the only output recipe: one naming only input registers, as setp and watchdog "
        "in UR's examples, is an input recipe)",
    )
    p.add_argument(
        "--frequency", type=float, default=125.0, metavar="HZ", help="output rate in Hz (default: 125)"
    )
    _add_stop_and_output(p)
    p.add_argument(
        "--wall-clock",
        action="store_true",
        help="add host_time, this host's receive time in seconds since the epoch (float64), beside "
        "the controller's timestamp: the time each socket read returned, spaced within a read by the "
        "controller's timestamp (default: off)",
    )
    p.set_defaults(run=run)


def _add_stop_and_output(p: argparse.ArgumentParser) -> None:
    """When the recording stops, and the file (or parts) it goes to."""
    stop = p.add_mutually_exclusive_group()
    stop.add_argument(
        "--duration",
        type=float,
        metavar="SECONDS",
        help="record SECONDS seconds of the controller's data: S x frequency rows (default: until Ctrl-C)",
    )
    stop.add_argument("--samples", type=int, metavar="ROWS", help="stop after ROWS rows (default: Ctrl-C)")
    p.add_argument(
        "-o", "--output", required=True, metavar="FILE", help="out.csv, .parquet, .jsonl or .mcap (required)"
    )
    p.add_argument(
        "--format", choices=("csv", "parquet", "jsonl", "mcap"), help="default: from the -o suffix"
    )
    p.add_argument(
        "--split",
        metavar="DURATION|SIZE",
        help="write closed parts of at most this long or big (60s, 10min, 1h, 100MB, 2GiB), as rosbag2 "
        "splits: -o run.parquet gives run_0000.parquet, run_0001.parquet, ..., each complete and "
        "renamed into place when full, so a kill or power loss costs at most the open part. Read them "
        "as one dataset: DuckDB read_parquet('run_*.parquet'), Polars scan_parquet('run_*.parquet'), "
        "pyarrow.dataset.dataset(sorted(glob('run_*.parquet'))). Parts of an earlier run with the same "
        "name are removed once this run's first part is in place (default: one file)",
    )


def names_of(args: argparse.Namespace, alternative: str = ", or the names with --fields A,B") -> list[str]:
    """The output names of --fields, or of the --recipe file's recipe (--recipe-key picks one)."""
    if args.fields:  # --fields a,b --fields c: all three, in order
        return [n.strip() for given in args.fields for n in given.split(",") if n.strip()]
    from rtde_spec.cli.arguments import catalogue_for
    from rtde_spec.recipes.files import load_recipes, pick_recipe

    path = existing_file(args.recipe)
    if path is None:
        raise UsageError(
            f"no such recipe file; give {RECIPE_FILE_HELP}{alternative}",
            subject=f"--recipe {args.recipe}",
        )
    cat = catalogue_for(args)
    inputs, outputs = set(cat.names("input")), set(cat.names("output"))
    key = getattr(args, "recipe_key", None)
    recipe = pick_recipe(load_recipes(path), key, "output", inputs, outputs, where=args.recipe)
    # the types a file declares (UR's XML) are checked as `validate` checks them: one message
    wrong = [
        f"{name}: the recipe says {declared}, the spec says {info.type}"
        for name in recipe.names
        if (declared := recipe.declared_types.get(name)) is not None
        and (info := cat.get(name, "output")) is not None
        and declared != info.type
    ]
    if wrong:
        from rtde_spec.errors import RecipeError

        which = f" (recipe {recipe.key})" if recipe.key else ""
        raise RecipeError(
            f"{'; '.join(wrong)}; correct the type{'' if len(wrong) == 1 else 's'} in the file "
            f"(`rtde-spec validate {args.recipe}` reports every problem)",
            subject=f"--recipe {args.recipe}{which}",
        )
    return list(recipe.names)


def run(args: argparse.Namespace) -> int:
    from rtde_spec.output.split import parse_split
    from rtde_spec.output.writers import open_writer
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.rtde.recorder import BATCH_SECONDS, record

    fmt = _checked_format(args)
    split = parse_split(args.split) if args.split else None
    names = names_of(args)
    _note_leftovers(Path(args.output), fmt)
    bar = _progress(args)
    # the reader wakes every ~0.1 s, half the recorder's write interval: no row waits longer
    batch = max(1, int(args.frequency * BATCH_SECONDS / 2))
    stop = _Stop()
    client = RtdeClient(args.host, args.port, timeout=args.timeout, batch=batch)
    with stop.handling():
        _connect(client, args)
    with stop.handling(), client:
        writer = open_writer(fmt, args.output, live=True, durable=True, split=split)
        if args.wall_clock:
            from rtde_spec.cli.wall_clock import ReceiveTimes, WallClockWriter

            received = ReceiveTimes()
            client.on_batch(received)  # before the recorder's own callback: times come first
            writer = cast("Writer", WallClockWriter(writer, received))
        try:
            stop.armed = True  # from here a signal ends the recording cleanly
            result = record(
                client,
                names,
                args.frequency,
                writer,
                duration=args.duration,
                samples=args.samples,
                progress=bar.update if bar is not None else None,
                stop=stop,
            )
        finally:
            writer.close()
            if bar is not None:
                bar.close()
    _report(args, result, names, client, writer if split is not None else None, stop)
    return 1 if result.stopped_by == "connection" else 0


def _checked_format(args: argparse.Namespace) -> str:
    """The output format, once every number the recording needs is checked (exit 2 otherwise)."""
    from rtde_spec.output.writers import format_for

    output_file(args.output)
    fmt = format_for(args.output, args.format)
    if fmt not in ("csv", "parquet", "jsonl", "mcap"):
        raise UsageError(f"-o {args.output}: use .csv, .parquet, .jsonl or .mcap (or --format)")
    if not 0 < args.frequency < float("inf"):  # NaN too; the controller's own limit is checked at setup
        raise UsageError(f"--frequency {args.frequency:g}: a rate in Hz above 0")
    for option, value in (("--duration", args.duration), ("--timeout", args.timeout)):
        if value is not None and not 0 < value < float("inf"):
            raise UsageError(f"{option} {value:g}: give seconds above 0")
    if args.samples is not None and args.samples < 1:
        raise UsageError(f"--samples {args.samples}: give a number of rows of 1 or more")
    return fmt


def _note_leftovers(output: Path, fmt: str) -> None:
    """Say what a recording killed before it closed left beside the output; drop empty ones."""
    from rtde_spec.output.tempnames import leftovers

    for path in leftovers(output):
        if _empty(path):  # killed before its first batch reached the file: nothing to keep
            path.unlink(missing_ok=True)
            continue
        what = (
            "a Parquet file without its footer: no reader opens it; --split bounds what a kill costs"
            if fmt == "parquet"
            else "its rows up to the last batch are readable"
        )
        print(
            f"note: {path} was left by a recording killed before it closed this file ({what})",
            file=sys.stderr,
        )


def _report(
    args: argparse.Namespace, result: Any, names: list[str], client: RtdeClient, parts_of: Any, stop: _Stop
) -> None:
    """The one summary line on stderr, and why a recording ended early."""
    how = result.stopped_by
    if how == "stop" and stop.signal is not None:
        how = signal.Signals(stop.signal).name
    where = args.output
    if parts_of is not None:
        parts = getattr(parts_of, "paths", [])
        where = f"{len(parts)} parts {parts[0]} .. {parts[-1]}" if parts else "no file"
    try:
        print(
            f"recorded {plural(result.rows, 'row')} of {plural(len(names), 'field')} in "
            f"{result.seconds:.1f} s to {where} "
            f"(controller {client.controller_version}, skipped {result.skipped}, stopped by {how})",
            file=sys.stderr,
        )
        if result.stopped_by == "connection":  # say why: a close, or a package cut off or broken
            lost = safe_text(str(client.connection_lost))  # may quote the controller's words
            print(f"error: the recording ended early: {lost}", file=sys.stderr)
    except OSError:  # SIGHUP: the terminal is gone; the file is what matters
        pass


def _connect(client: RtdeClient, args: argparse.Namespace) -> None:
    """Connect; when the handshake fails, say what listens on the port if it is not RTDE."""
    try:
        client.connect()
    except (RtdeSpecError, TimeoutError) as exc:
        client.close()
        from rtde_spec.cli.port_probe import handshake_error

        raise handshake_error(args, "rtde", exc)  # noqa: B904 (the cause is set)


def _empty(path: Path) -> bool:
    try:
        return path.stat().st_size == 0
    except OSError:
        return False


class _Stop:
    """Set by SIGINT, SIGTERM and SIGHUP: the recorder writes what it has and closes the file.

    Before `armed` (connecting) a signal stops at once; a second signal also does.
    The handler only sets an attribute: nothing in it takes a lock the main thread may hold.
    """

    def __init__(self) -> None:
        self.signal: int | None = None
        self.armed = False

    def is_set(self) -> bool:
        return self.signal is not None

    def _handle(self, signum: int, frame: object) -> None:
        if not self.armed or self.signal is not None:
            raise KeyboardInterrupt
        self.signal = signum

    @contextlib.contextmanager
    def handling(self) -> Iterator[None]:
        wanted = [getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)]
        if threading.current_thread() is not threading.main_thread():  # handlers live in the main thread
            yield
            return
        previous = {s: signal.signal(s, self._handle) for s in wanted}
        try:
            yield
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)


def _progress(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    total = args.samples or (int(args.duration * args.frequency) if args.duration else None)
    return tqdm(total=total, unit="rows", desc="record", file=sys.stderr)
