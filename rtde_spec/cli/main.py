"""rtde-spec: decode packages, list fields, validate recipes, run the demo.

Exit codes, the same for every subcommand:
  0    success
  1    an error in the data or the result (invalid recipe, bad bytes, a refused or
       dropped connection, a port that speaks another interface)
  2    a usage error (bad option, missing file, unknown controller version)
  3    capture read every input to its end, but some was damaged or skipped, or
       nothing decoded (the summary on stderr says what and where, and the TCP ports
       seen; --lenient makes it 0); plot wrote its image, but CSV cells that are not
       numbers are gaps in it (stderr names their lines)
  130  interrupted (Ctrl-C, SIGTERM, SIGHUP); what was written so far is whole
Errors print `error: WHAT: WHY; WHAT TO DO` on stderr; --debug shows the traceback.
tests/test_cli_errors.py holds each error a user can cause, with its message and code.
Subcommand modules import their heavy parts only when they run, so help and start-up
stay fast.
"""

from __future__ import annotations

import argparse
import errno
import logging
import os
import sys
import threading
from collections.abc import Callable
from typing import NoReturn

# numpy's OpenBLAS starts a thread per core when it loads, and they spin ~0.1 s of CPU while a
# command starts (40 % of a one-package capture's CPU). No command does linear algebra worth
# sharing (the emulator's 6x6 kinematics), so one thread; a user's own setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from rtde_spec import __version__
from rtde_spec.cli import (
    capture_cmd,
    decode_cmd,
    demo_cmd,
    examples_cmd,
    fields_cmd,
    plot_cmd,
    record_cmd,
    serve_cmd,
    spec_cmd,
    validate_cmd,
    watch_cmd,
    wireshark_cmd,
)
from rtde_spec.cli.conventions import GLOBAL_AFTER, add_global_options, leaf_parsers
from rtde_spec.cli.report import EXIT_ERROR, EXIT_USAGE
from rtde_spec.cli.standard_streams import discard_held_output, output_failure, set_up_streams
from rtde_spec.cli.stop_signals import restore, stop_on_terminate
from rtde_spec.errors import RtdeSpecError, UsageError, out_of_descriptors
from rtde_spec.printable import safe_text

COMMANDS = (
    examples_cmd,
    demo_cmd,
    decode_cmd,
    fields_cmd,
    validate_cmd,
    serve_cmd,
    record_cmd,
    watch_cmd,
    capture_cmd,
    plot_cmd,
    wireshark_cmd,
    spec_cmd,
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rtde-spec",
        description="Universal Robots RTDE and primary/secondary interfaces: spec, codec and tools.",
        epilog="Exit codes: 0 success; 1 error in the data or result; 2 usage error; 3 capture read "
        "every input but some was damaged or skipped, or nothing decoded (summary on stderr; --lenient "
        "gives 0), or plot's table had cells that are not numbers; 130 interrupted. Start with "
        "`rtde-spec examples DIR`: the files the README uses.",
    )
    parser.add_argument("--version", action="version", version=f"rtde-spec {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors (default: off)")
    parser.add_argument(
        "--extra-fields",
        action="append",
        default=[],
        metavar="YAML",
        help="add fields from a YAML file shaped like spec/rtde/fields.yaml (repeatable; default: none)",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in COMMANDS:
        module.add_parser(sub)
    for _words, leaf in leaf_parsers(parser):
        add_global_options(leaf)  # `rtde-spec fields --extra-fields x.yaml` works as well
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.extra_fields = [*args.extra_fields, *getattr(args, GLOBAL_AFTER, [])]
    run: Callable[[argparse.Namespace], int] = args.run
    previous = stop_on_terminate()
    try:
        return run(args)
    except BrokenPipeError:
        # the reader (e.g. `head`) closed the pipe: not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except UsageError as exc:
        if args.debug:
            raise
        print(f"error: {_printable(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    except (RtdeSpecError, OSError, ValueError) as exc:
        if args.debug:
            raise
        print(f"error: {_printable(_worded(exc))}", file=sys.stderr)  # errors quote the wire: escaped
        return EXIT_ERROR
    finally:
        restore(previous)


def entry() -> NoReturn:
    """The `rtde-spec` command (and `python -m rtde_spec`): `main()`, then the process ends
    without Python's teardown of every module and object (~45 ms at the end of a capture:
    numpy, pyarrow, the decoders' tables), which the operating system frees at once.

    By then every output is closed and in place; stdout and stderr are flushed here. Only when
    nothing else runs: a thread still alive, or an exception (a usage error's SystemExit
    included), leaves the usual way. Code calling `main()` itself is not affected."""
    set_up_streams()
    try:
        code = main()
    except SystemExit:  # --help, --version, a usage error: argparse ends the command
        if not _flushed():
            sys.exit(EXIT_ERROR)
        raise
    if not _flushed(said=code != 0):
        code = code or EXIT_ERROR
    if threading.active_count() > 1:  # not ours to cut short: Python joins them as usual
        sys.exit(code)
    try:
        sys.stderr.flush()
    except OSError:
        pass
    logging.shutdown()  # a user's handlers (a file) flushed and closed, as at a normal exit
    os._exit(code)


def _flushed(said: bool = False) -> bool:
    """Standard output flushed; False when that failed (a full disk: said on stderr, unless the
    command has `said` its error already). What it held is dropped either way, so Python's own
    flush at the end does not fail again."""
    try:
        sys.stdout.flush()
        failed = output_failure()
        if failed is not None:  # a write whose caller swallowed the error (argparse's help)
            raise failed
    except BrokenPipeError:  # the reader closed the pipe (`| head`): not an error of ours
        discard_held_output()
    except OSError as exc:  # a full disk under a redirected stdout: "standard output: ..."
        if not said:
            print(f"error: {_printable(_worded(exc))}", file=sys.stderr)
        discard_held_output()
        return False
    return True


def _printable(text: str) -> str:
    """An error's lines as lines (a spec's list of problems), control characters escaped in each:
    its newlines were printed as `\\x0a`, the list on one line."""
    return "\n".join(safe_text(line) for line in text.split("\n"))


def _worded(exc: BaseException) -> str:
    """The error's text; out of file descriptors, what the limit is and what to do."""
    if isinstance(exc, OSError) and exc.errno in (errno.EMFILE, errno.ENFILE):
        return out_of_descriptors()
    return str(exc)


if __name__ == "__main__":
    sys.exit(main())
