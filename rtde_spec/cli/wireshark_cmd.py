"""rtde-spec wireshark: install or locate the dissector generated from the spec."""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

from rtde_spec.cli.conventions import describe, place_copy
from rtde_spec.errors import UsageError

PLUGIN = "rtde_spec.lua"
DEFAULT_DIR = Path.home() / ".local" / "lib" / "wireshark" / "plugins"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "wireshark",
        help="install the Wireshark/tshark dissector generated from the spec (rtde.*, urprimary.*, "
        "urrealtime.*, urdashboard.*, urcl_reverse.*, urcl_trajectory.*, urcl_script_command.*, "
        "urcl_script_sender.*)",
        **describe(
            "Without --install, prints the dissector's path, for `tshark -X lua_script:PATH`. One Lua file "
            "holds every protocol of a driver session, each registered on its default port (RTDE 30004, "
            "primary 30001/30002/30011/30012, real-time 30003/30013, dashboard 29999, URCL 50001-50004); "
            "for moved ports use Wireshark's Decode As. --install copies it to the plugins folder (or -o).",
            "rtde-spec wireshark",
            "rtde-spec wireshark --install",
            "rtde-spec wireshark --install -o wireshark-plugins/",
        ),
    )
    p.add_argument("--install", action="store_true", help="copy it to the plugins folder (default: print)")
    p.add_argument(
        "-o", "--output", type=Path, default=DEFAULT_DIR, dest="dir", metavar="FOLDER",
        help=f"plugins folder to install into (default: {DEFAULT_DIR})",
    )  # fmt: skip
    p.add_argument("--dir", type=Path, dest="dir", help=argparse.SUPPRESS)  # the old spelling of -o
    p.set_defaults(run=run)


def dissector_path() -> Path:
    return Path(str(resources.files("rtde_spec._generated").joinpath(PLUGIN)))


def run(args: argparse.Namespace) -> int:
    source = dissector_path()
    if not args.install:
        print(source)
        return 0
    target = args.dir / PLUGIN
    if args.dir.exists() and not args.dir.is_dir():
        raise UsageError(
            f"is a file, not a folder; give -o the plugins folder to install {PLUGIN} into",
            subject=f"-o {args.dir}",
        )
    place_copy(  # a folder that cannot be written to: the -o given is the problem
        source,
        target,
        lambda why: UsageError(
            f"cannot install the dissector there ({target.name}: {why}); give -o a folder you can write "
            f"to (or load it without installing: tshark -X lua_script:{source})",
            subject=f"-o {args.dir}",
        ),
    )
    print(f"installed {target}; Wireshark and tshark load it at their next start")
    return 0
