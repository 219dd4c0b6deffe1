"""The main demo: emulator on loopback, our client records, a CSV and a PNG come out."""

from __future__ import annotations

import argparse
import csv
import logging
from pathlib import Path

from rtde_spec.output.text import table

DEMO_FIELDS = [
    "timestamp",
    "actual_q",
    "actual_TCP_pose",
    "robot_mode",
    "safety_status",
    "target_speed_fraction",
]
DEMO_SCENARIO = {
    "controller": "5.15.0",
    "outputs": {
        "actual_q": {
            "sine": {
                "amplitude": [0.8, 0.4, 0.5, 0.6, 0.9, 1.2],
                "period": 2.5,
                "phase": [0.0, 0.5, 1.0, 1.5, 2.0, 2.5],
                "offset": [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
            }
        },
        "actual_TCP_pose": {
            "sine": {
                "amplitude": [0.1, 0.1, 0.05, 0, 0, 0],
                "period": 2.5,
                "offset": [0.3, -0.2, 0.4, 3.14, 0, 0],
            }
        },
    },
}
RATE = 125.0


def run_online(args: argparse.Namespace) -> int:
    from rtde_spec.emulator.scenario import Scenario
    from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
    from rtde_spec.output.writers import open_writer
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.rtde.recorder import record

    logging.getLogger("rtde_spec").setLevel(logging.WARNING)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    csv_path, png_path = out / "joints.csv", out / "joints.png"
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, scenario=Scenario.model_validate(DEMO_SCENARIO)
    )
    with EmulatorThread(config) as emulator:
        port = emulator.ports["rtde"]
        print(f"Controller emulator {emulator.model.version} listening on 127.0.0.1:{port} (RTDE)")
        with RtdeClient("127.0.0.1", port) as client:
            print(
                f"Connected: protocol {client.protocol_version}, controller {client.controller_version}; "
                f"recording {', '.join(DEMO_FIELDS)} at {RATE:g} Hz for {args.seconds:g} s"
            )
            writer = open_writer("csv", csv_path)
            try:
                result = record(client, DEMO_FIELDS, RATE, writer, duration=args.seconds)
            finally:
                writer.close()
    print(f"\nWrote {result.rows} rows to {csv_path} (skipped {result.skipped})")
    rows = _read(csv_path)
    _summary(rows)
    _plot(rows, png_path)
    print("\nNext: rtde-spec serve (a controller for your own tests), rtde-spec record --host ROBOT ...,")
    print("      rtde-spec demo --offline (decoding without sockets), rtde-spec decode --help")
    return 0


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
    from rtde_spec.errors import MissingDependencyError
    from rtde_spec.output.plots import plot_columns

    try:
        plot_columns(
            columns, ["actual_q"], "timestamp", path, "Joint positions recorded from the controller emulator"
        )
    except MissingDependencyError:
        hint = "pip install 'rtde_spec[plot]'"
        print(f"\nNo plot: matplotlib is not installed ({hint}), then run again for {path}")
        return
    print(f"\nPlot: {path}")
