"""A driver session's capture to tables: packages per second across every protocol, beside tshark.

The session (bytes packed with struct, framed with dpkt) runs side by side for SECONDS of
capture time: URCL's reverse interface at 500 Hz (SERVOJ), RTDE outputs at 500 Hz, the
real-time interface at 125 Hz, a trajectory of points with its result every second,
script commands and dashboard requests. `capture` decodes it to Parquet (median of three,
after a warming run); tshark reads the same file with the generated dissector, once
printing a field of every protocol and once only `tcp.payload` (its floor).

    python benchmarks/bench_capture_driver.py [--seconds 60]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from rtde_spec.capture.decoder import CaptureSummary, decode_to_directory  # noqa: E402
from rtde_spec.cli.wireshark_cmd import dissector_path  # noqa: E402
from tests.capture_files import Conversation, rtde_raw_setup, write  # noqa: E402

ROBOT, PC = "192.168.56.101", "192.168.56.1"


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def session(path: Path, seconds: int) -> dict[str, int]:
    """Write the mixed capture; returns the packages sent per protocol."""
    reverse = Conversation((ROBOT, 40001), (PC, 50001))
    trajectory = Conversation((ROBOT, 40003), (PC, 50003))
    commands = Conversation((ROBOT, 40004), (PC, 50004))
    rtde = Conversation((PC, 42004), (ROBOT, 30004))
    realtime = Conversation((PC, 43003), (ROBOT, 30003))
    dashboard = Conversation((PC, 41999), (ROBOT, 29999))
    for conv in (reverse, trajectory, commands, rtde, realtime, dashboard):
        conv.handshake()
    rtde_raw_setup(rtde)
    dashboard.send("server", b"Connected: Universal Robots Dashboard Server\n")
    counts = dict.fromkeys(("reverse", "rtde", "realtime", "trajectory", "script_command", "dashboard"), 0)
    body = bytearray(1116)
    struct.pack_into(">i", body, 0, 1116)
    for step in range(seconds * 500):
        t = step * 0.002
        q = [round((0.001 * step + j) * 1e6) % 3_000_000 for j in range(6)]
        reverse.send("server", words(20, *q, 1), dt=0.002)
        rtde.send("server", struct.pack(">HBBd6d", 60, ord("U"), 1, t, *(x / 1e6 for x in q)), dt=0.002)
        counts["reverse"] += 1
        counts["rtde"] += 1
        if step % 4 == 0:
            struct.pack_into(">d6d", body, 4, t, *(x / 1e6 for x in q))
            realtime.send("server", bytes(body), dt=0.008)
            counts["realtime"] += 1
        if step % 50 == 0:  # 10 trajectory points a second, a result each second
            trajectory.send(
                "server", words(*q, *[0] * 6, 1_000_000, 1_400_000, 0, 0, 0, 0, 100_000, 0, 0), dt=0.1
            )
            counts["trajectory"] += 1
        if step % 500 == 499:
            trajectory.send("client", words(0), dt=0.001)
            commands.send("server", words(1, 1_500_000, 0, 0, 50_000, *[0] * 23), dt=1.0)
            dashboard.send("client", b"robotmode\n", dt=1.0)
            dashboard.send("server", b"Robotmode: RUNNING\n", dt=0.004)
            counts["trajectory"] += 1
            counts["script_command"] += 1
            counts["dashboard"] += 2
    write(path, [reverse, trajectory, commands, rtde, realtime, dashboard])
    return counts


def row(label: str, seconds: float, packages: int) -> None:
    print(f"{label:48s} {seconds:7.2f} s  {packages / seconds:10,.0f} packages/s")


def timed(args: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--seconds", type=int, default=60, help="capture seconds of the session (default: 60)"
    )
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-driver-"))
    try:
        path = work / "driver.pcap"
        sent = session(path, args.seconds)
        decode_to_directory(path, work / "warm", "parquet")  # imports and first-call set-up
        times: list[float] = []
        summary: CaptureSummary | None = None
        for _ in range(3):
            shutil.rmtree(work / "out", ignore_errors=True)
            start = time.perf_counter()
            summary = decode_to_directory(path, work / "out", "parquet")
            times.append(time.perf_counter() - start)
        assert summary is not None
        assert not summary.damage(), summary.damage()
        packages = summary.packages
        size = path.stat().st_size / 1e6
        print(f"driver session: {args.seconds} s, {size:.1f} MB, sent {sent}")
        print(f"tables: {dict(sorted(summary.tables.items()))}")
        best = statistics.median(times)
        row("rtde-spec capture (Parquet, median of 3)", best, packages)
        tshark = shutil.which("tshark")
        if tshark is None:
            print("tshark: not installed")
            return
        fields = ["urcl_reverse.target", "rtde.actual_q", "urrealtime.q_actual", "urcl_trajectory.target",
                  "urcl_script_command.mass", "urdashboard.outcome"]  # fmt: skip
        full = [tshark, "-X", f"lua_script:{dissector_path()}", "-r", str(path), "-T", "fields"]
        for f in fields:
            full += ["-e", f]
        seconds = timed(full)
        row("tshark + generated dissector, 6 fields", seconds, packages)
        seconds = timed([tshark, "-r", str(path), "-T", "fields", "-e", "tcp.payload"])
        row("tshark -T fields -e tcp.payload (no dissector)", seconds, packages)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
