"""The main demo: emulator on loopback, a motion program runs, our client records, a CSV and a PNG
come out."""

from __future__ import annotations

import argparse
import csv
import logging
import threading
from pathlib import Path

from rtde_spec.cli.conventions import plural
from rtde_spec.output.text import table

DEMO_FIELDS = [
    "timestamp",
    "actual_q",
    "actual_TCP_pose",
    "robot_mode",
    "safety_status",
    "target_speed_fraction",
]
# a short motion program, sent to the emulator's primary port once recording runs: the first
# plot a new user sees is a moving arm (joint moves, a straight line of the tool, home again)
DEMO_PROGRAM = """def demo_motion():
  movej([0.6, -1.3, 1.3, -1.6, -1.4, 0.5], a=4.0, v=2.5)
  movel(pose_add(get_actual_tcp_pose(), p[0.0, 0.1, 0.05, 0, 0, 0]), a=1.5, v=0.4)
  movej([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0], a=4.0, v=2.5)
end
"""
PROGRAM_DELAY = 0.3  # s of the arm at rest before the program starts
RATE = 125.0


def run_online(args: argparse.Namespace) -> int:
    from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
    from rtde_spec.output.writers import open_writer
    from rtde_spec.primary.client import PrimaryClient
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.rtde.recorder import record

    logging.getLogger("rtde_spec").setLevel(logging.WARNING)
    out = demo_folder(args.output)
    csv_path, png_path = out / "joints.csv", out / "joints.png"
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, realtime_port=None, dashboard_port=None
    )
    with EmulatorThread(config) as emulator:
        port, primary = emulator.ports["rtde"], emulator.ports["primary"]
        print(
            f"Controller emulator {emulator.model.version} listening on 127.0.0.1: RTDE {port}, "
            f"primary {primary}"
        )
        with RtdeClient("127.0.0.1", port) as client, PrimaryClient("127.0.0.1", primary) as robot:
            print(
                f"Connected: protocol {client.protocol_version}, controller {client.controller_version}; "
                f"recording {', '.join(DEMO_FIELDS)} at {RATE:g} Hz for {args.seconds:g} s"
            )
            print(f"Sending this URScript to the primary port after {PROGRAM_DELAY:g} s:\n")
            print("    " + DEMO_PROGRAM.rstrip().replace("\n", "\n    ") + "\n")
            timer = threading.Timer(PROGRAM_DELAY, robot.send_script, (DEMO_PROGRAM,))
            writer = open_writer("csv", csv_path)
            try:
                timer.start()
                result = record(client, DEMO_FIELDS, RATE, writer, duration=args.seconds)
                writer.prepare()  # finished beside its name: in place with its plot, or not at all
            except BaseException:
                writer.abort()
                raise
            finally:
                timer.cancel()
                timer.join()
    finished = writer.part.temp if writer.part is not None else csv_path
    rows = _read(finished)
    try:
        _summary(rows)
        _plot(rows, png_path)  # a plot that fails (a full disk) leaves the earlier pair as it was
    except BaseException:
        writer.abort()
        raise
    writer.commit()
    interrupted = result.stopped_by == "interrupt"
    early = f"; stopped early by Ctrl-C after {result.seconds:.1f} s" if interrupted else ""
    print(f"\nWrote {plural(result.rows, 'row')} to {csv_path} (skipped {result.skipped}{early})")
    print("\nNext: rtde-spec serve (a controller for your own tests), rtde-spec record --host ROBOT ...,")
    print("      rtde-spec demo --offline (decoding without sockets), rtde-spec decode --help")
    return 0


def demo_folder(given: Path | None) -> Path:
    """The folder -o names (made if missing; a file is refused), else a new temporary one:
    the demo never leaves files in the folder it was started from."""
    import tempfile

    from rtde_spec.cli.conventions import output_folder

    if given is None:
        return Path(tempfile.mkdtemp(prefix="rtde-demo-"))
    out = output_folder(str(given))
    out.mkdir(parents=True, exist_ok=True)
    return out


def _read(path: Path) -> dict[str, list[float]]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns: dict[str, list[float]] = {name: [] for name in reader.fieldnames or []}
        for row in reader:
            for name, value in row.items():
                columns[name].append(float(value))
    return columns


def _summary(columns: dict[str, list[float]]) -> None:
    names = [f"actual_q_{i}" for i in range(6)]
    rows = [[n, f"{min(columns[n]):.3f}", f"{max(columns[n]):.3f}", f"{columns[n][-1]:.3f}"] for n in names]
    t = columns["timestamp"]
    mode = int(columns["robot_mode"][-1])
    print(f"Controller time {t[0]:.3f} .. {t[-1]:.3f} s; robot_mode {mode} (RUNNING = 7)\n")
    print(table(["joint position [rad]", "min", "max", "last"], rows))


def _plot(columns: dict[str, list[float]], path: Path) -> None:
    from rtde_spec.errors import MissingDependencyError, install_hint
    from rtde_spec.output.plots import plot_columns

    try:
        plot_columns(
            columns, ["actual_q"], "timestamp", path, "Joint positions of a motion program on the emulator"
        )
    except MissingDependencyError:
        hint = install_hint("plot")
        print(f"\nNo plot: matplotlib is not installed ({hint}), then run again for {path}")
        return
    print(f"\nPlot: {path}")
