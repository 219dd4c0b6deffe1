"""The emulator at 500 Hz to four clients, and the receive loop's CPU per package, side by side.

1. `rtde-spec serve` in its own process; four clients subscribe to ur_rtde's 58-field
   recipe at 500 Hz for `--seconds`; every package's arrival is stamped. Reported:
   missed packages (gaps in the controller timestamp) and the p99 lateness of each
   package against its due time (first arrival + controller time elapsed).
2. Receive-loop CPU per package (`receive_loops.py`), each loop in its own process
   against the same emulator for `--seconds` / 2, `--rounds` rounds in a rotated order:
   ours waking per package (`for record in client`, `receive()`, `on_data`) and batched
   (`batch=50` / `100`, `on_data`; `batch=50`, `on_batch`: numpy arrays); the UR-client-style loop; ur_rtde's
   RTDEReceiveInterface (if installed); UR's own client (`--ur-client CHECKOUT`: a checkout
   of UR's RTDE_Python_Client_Library, which is not on PyPI; its `receive()` loop, as UR's
   examples run it, becomes the peer of the issue-30 ratios); floors: a bare `recv()` loop, the same with one
   `struct` unpack, batched `recv` + `struct` tuples. Medians, spread, wake-ups per
   package, medians of per-round ratios, the load average. Then the warm in-process rows
   (our code's own cost over the floor) and system calls per package under strace.
   `--receive-only`: only this.

3. With --motion, only this (the rows above are unchanged without it): the emulator
   (5.15, 500 Hz) in its own process while a motion program runs (movej back and forth,
   sent to its primary port), eight clients at 500 Hz on RTDE and one on the real-time
   port. Reported: missed packages, the p99 of each control step's lateness against its
   due time (measured in the emulator's loop), and the emulator process's CPU per control
   step (everything: motion, kinematics, RTDE to eight clients, real-time, Robot State).

Targets: no missed packages, p99 lateness <= 1 ms; batch=50 <= 8 µs/package and >= 10x
less than the UR-client-style loop. Issue 30 (printed): `for record in client` <= 15 µs
and >= 6x less than the UR-client-style loop; batched <= 4 µs and >= 20x.

4. With --control-script, only this: ur_rtde's control program with a servoJ stream at 500 Hz
   and four readers (bench_control_script.py).

    python benchmarks/bench_emulator.py [--seconds 10] [--rounds 3] [--ur-client CHECKOUT]
        [--receive-only | --motion | --control-script]
    python benchmarks/bench_emulator.py --control-script --seconds 60 [--realtime 10] [--nice -10]
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
from receive_loops import receive_rows, specs, syscall_rows, ur_rtde_row, warm_rows
from timing_client import TIMING

TARGET_P99_MS = 1.0
RATE = 500.0
ROUNDS = 5  # of every receive-loop row, in a rotated order each round


def serve(host: str, port: int) -> tuple[subprocess.Popen[str], int]:
    cmd = [sys.executable, "-m", "rtde_spec", "serve", "--host", host, "--rtde-port", str(port)]
    proc = subprocess.Popen(
        # no real-time or dashboard port: they would take 127.0.0.1:30003 and :29999 from the tests
        [
            *cmd,
            "--primary-port",
            "0",
            "--secondary-port",
            "0",
            "--realtime-port",
            "-1",
            "--dashboard-port",
            "-1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()
    return proc, int(re.search(r"rtde (\d+)", line).group(1))  # type: ignore[union-attr]


def four_clients(port: int, seconds: float) -> list[dict[str, float]]:
    """Four light client processes (raw sockets, a timestamp each), so the figure is the emulator's."""
    names = ",".join(UR_RTDE_DEFAULT_OUTPUTS)  # timestamp first: the client reads it at byte 4
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", TIMING, "127.0.0.1", str(port), str(seconds), names],
            stdout=subprocess.PIPE,
            text=True,
        )
        for _ in range(4)
    ]
    return [json.loads(p.communicate(timeout=seconds + 30)[0].strip().splitlines()[-1]) for p in procs]


MOTION_EMULATOR = """
import json, sys, time
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
config = EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, realtime_port=0, dashboard_port=None,
                        controller="5.15.0", step_timing=1_000_000)
with EmulatorThread(config) as emu:
    print(json.dumps(emu.ports), flush=True)
    sys.stdin.readline()  # the clients are streaming: measure from here
    e = emu.emulator
    c0, s0 = time.process_time(), emu.model.step
    e.step_lateness.clear()
    sys.stdin.readline()
    c1, s1 = time.process_time(), emu.model.step
    late = sorted(e.step_lateness)
    print(json.dumps({"steps": s1 - s0, "cpu_us": (c1 - c0) / (s1 - s0) * 1e6, "late_steps": e.late_steps,
                      "p99_ms": late[int(len(late) * 0.99)] * 1000, "max_ms": late[-1] * 1000,
                      "moving": emu.model.arm.moving}), flush=True)
    sys.stdin.readline()  # the clients are done: only then the ports close
"""
MOTION_CLIENTS = 8


def motion_program(seconds: float) -> str:
    """movej back and forth for about `seconds` (each move about 0.6 s)."""
    a = "[0.6, -1.3, 1.3, -1.6, -1.4, 0.5]"
    b = "[-0.6, -1.8, 1.8, -1.5, -1.7, -0.5]"
    moves = [f"  movej({a if i % 2 == 0 else b}, a=4.0, v=2.5)" for i in range(int(seconds / 0.5) + 4)]
    return "def bench_motion():\n" + "\n".join(moves) + "\nend\n"


def motion_run(seconds: float) -> bool:
    """Eight 500 Hz RTDE clients and a real-time client while a program moves the arm."""
    import socket

    emu = subprocess.Popen(
        [sys.executable, "-c", MOTION_EMULATOR], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert emu.stdin is not None and emu.stdout is not None
    try:
        ports = json.loads(emu.stdout.readline())
        names = ",".join(UR_RTDE_DEFAULT_OUTPUTS)
        clients = [
            subprocess.Popen(
                [sys.executable, "-c", TIMING, "127.0.0.1", str(ports["rtde"]), str(seconds + 1), names],
                stdout=subprocess.PIPE, text=True,
            )
            for _ in range(MOTION_CLIENTS)
        ]  # fmt: skip
        realtime = socket.create_connection(("127.0.0.1", ports["realtime"]))
        with socket.create_connection(("127.0.0.1", ports["primary"])) as primary:
            primary.sendall(motion_program(seconds + 2).encode())
            import time

            time.sleep(1.0)  # the clients have set up
            emu.stdin.write("start\n")
            emu.stdin.flush()
            received, end = 0, time.monotonic() + seconds - 1
            realtime.settimeout(2)
            while time.monotonic() < end:
                received += len(realtime.recv(1 << 16))
            emu.stdin.write("stop\n")
            emu.stdin.flush()
            stats = json.loads(emu.stdout.readline())
        realtime.close()
        rows = [json.loads(c.communicate(timeout=seconds + 60)[0].strip().splitlines()[-1]) for c in clients]
        emu.stdin.write("quit\n")
        emu.stdin.flush()
    finally:
        emu.kill()
        emu.wait(10)
    missed = sum(r["missed"] for r in rows)
    client_p99 = max(r["p99_ms"] for r in rows)
    print(f"\nemulator with a motion program: {MOTION_CLIENTS} RTDE clients x 58 fields at {RATE:g} Hz "
          f"+ 1 real-time client, {seconds:g} s")  # fmt: skip
    print(f"  arm moving at the end: {stats['moving']}; real-time bytes received: {received}")
    print(
        f"  missed packages (all RTDE clients): {missed:.0f}; p99 lateness at the clients {client_p99:.2f} ms"
    )
    print(
        f"  control steps measured: {stats['steps']}, late steps skipped: {stats['late_steps']}; "
        f"step lateness p99 {stats['p99_ms']:.3f} ms, max {stats['max_ms']:.2f} ms"
    )
    print(f"  emulator CPU per control step: {stats['cpu_us']:.0f} µs (of {1e6 / RATE:.0f} µs per step)")
    ok = missed == 0 and stats["p99_ms"] <= TARGET_P99_MS and stats["moving"]
    print(
        f"  targets: no missed packages, step lateness p99 <= {TARGET_P99_MS} ms: {'met' if ok else 'MISSED'}"
    )
    return ok


def cat_type(catalogue: Any, name: str) -> str:
    return catalogue.get(name, "output").type  # type: ignore[no-any-return]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="length of each run (default: 10)")
    parser.add_argument("--assert-targets", action="store_true", help="exit 1 on a missed target")
    parser.add_argument(
        "--motion", action="store_true", help="only the run with a motion program and eight clients"
    )
    parser.add_argument(
        "--control-script", action="store_true", help="only ur_rtde's control script with a servoJ stream"
    )
    parser.add_argument("--host", default=None, help="--control-script: the emulator's loopback address")
    parser.add_argument(
        "--realtime", type=int, metavar="PRIORITY", help="--control-script: the emulator's loop at SCHED_FIFO"
    )
    parser.add_argument("--nice", type=int, default=0, help="--control-script: the emulator's niceness")
    parser.add_argument("--profile", metavar="FILE", help="--control-script: cProfile of the emulator's loop")
    parser.add_argument("--rounds", type=int, default=ROUNDS, help="rounds of the receive-loop rows")
    parser.add_argument(
        "--receive-only", action="store_true", help="only the receive-loop rows (not the four timing clients)"
    )
    parser.add_argument(
        "--against", metavar="CHECKOUT", help="also run our per-package and batch=50 rows from this checkout"
    )
    parser.add_argument(
        "--ur-client",
        metavar="CHECKOUT",
        help="a checkout of UR's RTDE_Python_Client_Library (not on PyPI): its receive() loop is the peer",
    )
    parser.add_argument("--no-warm", action="store_true", help="skip the warm in-process receive rows")
    parser.add_argument("--no-syscalls", action="store_true", help="skip the strace count of system calls")
    args = parser.parse_args(argv)
    if args.control_script:
        from bench_control_script import HOST
        from bench_control_script import run as control_script_run

        ok = control_script_run(args.seconds, args.host or HOST, args.realtime, args.nice, args.profile)
        return 0 if ok or not args.assert_targets else 1
    if args.motion:
        ok = motion_run(args.seconds)
        return 0 if ok or not args.assert_targets else 1
    proc, port = serve("127.0.0.1", 0)
    ok = True
    try:
        if not args.receive_only:
            print(f"emulator: 4 clients x 58 fields at {RATE:g} Hz for {args.seconds:g} s")
            timed = four_clients(port, args.seconds)
            for i, r in enumerate(timed):
                print(
                    f"  client {i}: {r['packages']:.0f} packages, missed {r['missed']:.0f}, "
                    f"p99 lateness {r['p99_ms']:.2f} ms, max {r['max_ms']:.2f} ms"
                )
            p99 = max(r["p99_ms"] for r in timed)
            missed = sum(r["missed"] for r in timed)
            ok = missed == 0 and p99 <= TARGET_P99_MS
            got = f"no missed packages (got {missed:.0f}), p99 <= {TARGET_P99_MS} ms (got {p99:.2f})"
            print(f"  targets: {got}")

        from rtde_spec import Catalogue, RecipeCodec

        names = list(UR_RTDE_DEFAULT_OUTPUTS)
        types = [cat_type(Catalogue.builtin(), n) for n in names]
        codec = RecipeCodec.for_names(names, "output")
        fmt = codec.struct.format[1:]
        verdicts = receive_rows(
            port, args.seconds / 2, args.rounds, names, types, codec.size, fmt, args.against, args.ur_client
        )
        proc.terminate()
        proc.wait(10)
        ur_rtde_row(serve, args.seconds)
        if not args.no_warm:
            warm_rows(against=args.against)
        if not args.no_syscalls:
            proc, port = serve("127.0.0.1", 0)
            syscall_rows(specs(port, 4.0, names, types, codec.size, fmt))
        ok = ok and verdicts["recording"]  # the recorder's batch is the one for the CPU target
    finally:
        proc.terminate()
        proc.wait(10)
    print(f"\n{'met' if ok else 'MISSED'}")
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
