"""ur_rtde's control program running in the emulator: a servoJ stream at 500 Hz and four more readers.

The emulator (5.15, UR5e, 500 Hz) runs in its own process on its own loopback address with
ur_rtde's fixed ports; ur_rtde's RTDEControlInterface uploads its 1,175-line control script
and streams servoJ targets at 500 Hz from another process (initPeriod/waitPeriod), beside
four light RTDE readers of the 58-field recipe at 500 Hz. Reported: missed packages at the
readers, each control step's lateness against its due time (p99, measured in the emulator's
loop), the URScript interpreter's CPU per control step (all the program's threads) and the
emulator process's CPU per step, and how closely the arm followed (the last target).

Lateness is when the loop woke against the step's due time (the step's packages leave right
after, before the next step's program runs); busy is how long the step then worked. The load
average is printed: on a shared machine the operating system, not the loop, decides the tail.
`--realtime P` runs the emulator's loop thread at SCHED_FIFO priority P (as a controller runs
its loop; needs CAP_SYS_NICE), `--nice N` the emulator process at niceness N, `--profile FILE`
writes cProfile statistics of the loop while measured.

Targets: 0 missed packages, step lateness p99 < 0.5 ms.

    python benchmarks/bench_emulator.py --control-script [--seconds 60] [--realtime 10] [--nice -10]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
from timing_client import TIMING

HOST = "127.0.0.97"  # its own address: ur_rtde needs the fixed ports
TARGET_P99_MS = 0.5

EMULATOR = """
import gc, json, os, sys, time
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
host, options = sys.argv[1], json.loads(sys.argv[2])
profile = options.pop("profile", None)  # a file: cProfile of the loop's thread while measured
config = EmulatorConfig(host=host, realtime_port=30003, dashboard_port=29999, controller="5.15.0", arm="UR5e",
                        step_timing=1_000_000, **options)
pauses = []
def timed(phase, info, began=[0.0]):
    if phase == "start":
        began[0] = time.perf_counter()
    else:
        pauses.append(time.perf_counter() - began[0])
faults = []
with EmulatorThread(config) as emu:
    emit = emu.model.emit
    def kept(event):
        if event.kind == "runtime_exception":
            faults.append(f"{event.text} (line {event.line})")
        emit(event)
    emu.model.emit = kept
    print("ready", flush=True)
    sys.stdin.readline()  # the servoJ stream and the readers run: measure from here
    e, model = emu.emulator, emu.model
    program = model.program
    c0, s0, i0 = time.process_time(), model.step, program.cpu if program else 0.0
    e.step_lateness.clear()
    e.step_busy.clear()
    e.step_sent.clear()
    late0 = e.late_steps
    gc.callbacks.append(timed)
    if profile:
        import cProfile
        profiler = cProfile.Profile()
        emu.call(profiler.enable)
    sys.stdin.readline()
    if profile:
        emu.call(profiler.disable)
        profiler.dump_stats(profile)
    gc.callbacks.remove(timed)
    c1, s1 = time.process_time(), model.step
    i1 = program.cpu if program else 0.0
    late, busy, sent = sorted(e.step_lateness), sorted(e.step_busy), sorted(e.step_sent)
    def q(xs, f):
        return xs[min(len(xs) - 1, int(len(xs) * f))] * 1000
    print(json.dumps({"steps": s1 - s0, "cpu_us": (c1 - c0) / (s1 - s0) * 1e6,
                      "interp_us": (i1 - i0) / (s1 - s0) * 1e6, "late_steps": e.late_steps - late0,
                      "p50_ms": q(late, 0.5), "p90_ms": q(late, 0.9), "p99_ms": q(late, 0.99),
                      "max_ms": late[-1] * 1000, "busy_p50_ms": q(busy, 0.5), "busy_p99_ms": q(busy, 0.99),
                      "sent_p50_ms": q(sent, 0.5), "sent_p99_ms": q(sent, 0.99),
                      "gc_runs": len(pauses), "gc_max_ms": max(pauses, default=0.0) * 1000,
                      "policy": emu.call(os.sched_getscheduler, 0),
                      "running": model.program is program and program is not None,
                      "threads": len(program.threads) if program else 0, "faults": faults[:3]}), flush=True)
    sys.stdin.readline()
"""

SERVO = """
import json, sys, time
import rtde_control, rtde_receive
host, seconds = sys.argv[1], float(sys.argv[2])
control = rtde_control.RTDEControlInterface(host)
receive = rtde_receive.RTDEReceiveInterface(host)
print("connected", flush=True)
sys.stdin.readline()
start = receive.getActualQ()
q, sent, end = list(start), 0, time.monotonic() + seconds
while time.monotonic() < end:
    period = control.initPeriod()
    q = [start[0] + 0.2 * (sent % 2500) / 2500, *start[1:5], start[5] - 0.1 * (sent % 2500) / 2500]
    control.servoJ(q, 0.5, 0.5, 0.002, 0.1, 300)
    sent += 1
    control.waitPeriod(period)
time.sleep(0.1)
error = max(abs(a - b) for a, b in zip(receive.getActualQ(), q))
control.servoStop()
control.stopScript()
print(json.dumps({"sent": sent, "rate": sent / seconds, "error": error}), flush=True)
"""


def run(
    seconds: float, host: str = HOST, realtime: int | None = None, nice: int = 0, profile: str | None = None
) -> bool:
    """One run; `realtime`: the emulator's loop at SCHED_FIFO this priority, `nice`: its niceness,
    `profile`: a file for cProfile's statistics of the emulator's loop while measured."""
    options: dict[str, object] = {"realtime_priority": realtime} if realtime is not None else {}
    if profile:
        options["profile"] = profile
    prefix = ["nice", "-n", str(nice)] if nice else []
    load_before = os.getloadavg()
    emu = subprocess.Popen(
        [*prefix, sys.executable, "-c", EMULATOR, host, json.dumps(options)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert emu.stdin is not None and emu.stdout is not None
    try:
        assert emu.stdout.readline().strip() == "ready"
        servo = subprocess.Popen(
            [sys.executable, "-c", SERVO, host, str(seconds)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert servo.stdin is not None and servo.stdout is not None
        assert servo.stdout.readline().strip() == "connected", "ur_rtde did not connect"
        names = ",".join(UR_RTDE_DEFAULT_OUTPUTS)
        readers = [
            subprocess.Popen(
                [sys.executable, "-c", TIMING, host, "30004", str(seconds + 1), names],
                stdout=subprocess.PIPE, text=True,
            )
            for _ in range(4)
        ]  # fmt: skip
        time.sleep(1.0)  # the readers have set up
        servo.stdin.write("go\n")
        servo.stdin.flush()
        emu.stdin.write("start\n")
        emu.stdin.flush()
        time.sleep(seconds - 0.5)
        emu.stdin.write("stop\n")
        emu.stdin.flush()
        stats = json.loads(emu.stdout.readline())
        stream = json.loads(servo.communicate(timeout=seconds + 30)[0].strip().splitlines()[-1])
        rows = [json.loads(r.communicate(timeout=seconds + 60)[0].strip().splitlines()[-1]) for r in readers]
        emu.stdin.write("quit\n")
        emu.stdin.flush()
    finally:
        emu.kill()
        emu.wait(10)
    missed = sum(r["missed"] for r in rows)
    reader_p99 = max(r["p99_ms"] for r in rows)
    load_after = os.getloadavg()
    how = (
        f"SCHED_FIFO {realtime}" if stats["policy"] == getattr(os, "SCHED_FIFO", None) else "normal priority"
    )
    how += f", nice {nice}" if nice else ""
    print(
        f"ur_rtde's control script in the emulator: servoJ at 500 Hz + 4 RTDE readers, {seconds:g} s ({how})"
    )
    print(
        f"  machine: {os.cpu_count()} cores, load average {load_before[0]:.1f} before, "
        f"{load_after[0]:.1f} after"
    )
    print(f"  servoJ commands sent: {stream['sent']} ({stream['rate']:.0f}/s); last target followed to "
          f"{stream['error']:.2e} rad")  # fmt: skip
    print(f"  program running at the end: {stats['running']}, with {stats['threads']} threads")
    for fault in stats["faults"]:
        print(f"  runtime exception: {fault}")
    print(f"  missed packages (4 readers): {missed:.0f}; reader p99 lateness {reader_p99:.2f} ms")
    print(
        f"  control steps measured: {stats['steps']}, late steps skipped: {stats['late_steps']}; "
        f"step lateness p50 {stats['p50_ms']:.3f} ms, p90 {stats['p90_ms']:.3f} ms, "
        f"p99 {stats['p99_ms']:.3f} ms, max {stats['max_ms']:.2f} ms"
    )
    print(f"  packages written (after the due time): p50 {stats['sent_p50_ms']:.3f} ms, "
          f"p99 {stats['sent_p99_ms']:.3f} ms")  # fmt: skip
    print(f"  step busy (send + next step's arm and program): p50 {stats['busy_p50_ms']:.3f} ms, "
          f"p99 {stats['busy_p99_ms']:.3f} ms; garbage collections {stats['gc_runs']}, "
          f"longest {stats['gc_max_ms']:.2f} ms")  # fmt: skip
    print(f"  interpreter CPU per control step: {stats['interp_us']:.1f} µs; "
          f"emulator process CPU per step: {stats['cpu_us']:.0f} µs (of 2000 µs)")  # fmt: skip
    ok = missed == 0 and stats["p99_ms"] < TARGET_P99_MS and stats["running"]
    print(f"  targets: 0 missed, step lateness p99 < {TARGET_P99_MS} ms: {'met' if ok else 'MISSED'}")
    return ok
