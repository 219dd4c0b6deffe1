"""Receive-loop CPU per package at 500 Hz: ours, the peers and the floors, side by side.

Each loop runs in its own process against one emulator (`rtde-spec serve`) for a few
seconds and reports its CPU per package (`process_time`: every thread) and its
wake-ups per package (voluntary context switches, every thread). Rows, in every round:

- ours, one wake-up per package: `for record in client` (the README's loop),
  `client.receive()` in a loop, records to an `on_data` callback (the consumer keeps
  the newest, as the UR-style loop does);
- ours batched: `batch=50` and `batch=100` (one wake-up per 100 / 200 ms), `on_data`; and
  `batch=50` with `on_batch` (a numpy array per read: no Python object per package);
- the peer: a UR-client-style loop (recv header, recv body, unpack, a dict per package,
  as UR's rtde.py does); ur_rtde's RTDEReceiveInterface once, when installed;
- floors: a bare `recv()` loop that decodes nothing (what one wake-up per package
  costs this machine), the same loop with one `struct` unpack per package, and
  batched `recv` + `struct` tuples (no names, no checks, no thread), the same with one
  numpy view per read instead of tuples (`on_batch`'s floor); and the bare loop
  in C (`recv_floor.c`, built with the machine's C compiler when it has one): what a
  wake-up costs with no interpreter, below which no Python loop can go.

The rows run in turn, in a rotated order each round (no row always follows the same
one); medians and the spread (lowest-highest) are reported, ratios are taken within
each round and their medians reported, with the load average before and after.

Load-independent rows: `warm_rows` sends one package and takes it, in one process
(a scripted controller on loopback, caches warm), so what is left over the floor is
our own code's cost; `syscall_rows` counts the system calls of each per-package loop
under `strace -c -f` (attached for a window once the loop runs), ours against the floor.
"""

from __future__ import annotations

import atexit
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

RATE = 500.0
BATCH = 50  # packages per reader wake-up in the batched row: 100 ms at 500 Hz, as `rtde-spec record`
BATCH_LONG = 100  # and one wake-up per 200 ms: what a wake-up itself costs shows in the difference
TARGET_US = 8.0  # the recording path (batch=50): CPU per package
TARGET_VS_UR = 10.0
TARGET_ITER_US = 15.0  # issue 30: the plain `for record in client` loop
TARGET_ITER_VS_UR = 6.0
TARGET_BATCH_US = 4.0  # issue 30: the batched / on_data path
TARGET_BATCH_VS_UR = 20.0

# every child ends with one JSON line: CPU (all threads), packages, wake-ups (voluntary switches)
RUSAGE = """
import resource
def _switches():
    return resource.getrusage(resource.RUSAGE_SELF).ru_nvcsw
def report(cpu, packages, wakes, **more):
    print(json.dumps({"cpu": cpu, "packages": packages, "wakeups": wakes, **more}), flush=True)
def ready():
    print("ready", flush=True)  # the loop runs: a syscall count may attach now
"""

OURS = (
    f"BATCH = {BATCH}\n"
    + """
import functools, json, sys, time
from rtde_spec import RtdeClient
"""
    + RUSAGE
    + """
port, seconds, names, mode = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3].split(","), sys.argv[4]
batch = int(sys.argv[5]) if len(sys.argv) > 5 else BATCH if mode.endswith("batched") else 1
with RtdeClient("127.0.0.1", port, queue_size=100000, batch=batch) as c:
    c.setup_outputs(names, 500.0)
    newest = [None]
    if mode.startswith("callback"):  # records handed over in the reader thread; the consumer
        c.on_data(functools.partial(newest.__setitem__, 0))  # keeps the newest, as the UR-style loop
    elif mode.startswith("array"):  # a numpy array per read; the consumer keeps the newest row
        c.on_batch(lambda array: newest.__setitem__(0, array[-1]))
    c.start()
    while c.received == 0:
        time.sleep(0.001)
    ready()
    t0, c0, n0, w0 = time.monotonic(), time.process_time(), c.received, _switches()
    if mode.startswith(("callback", "array")):
        time.sleep(seconds)
    elif mode == "iterate":
        for record in c:  # the README's loop, as a user writes it
            if time.monotonic() - t0 >= seconds:
                break
    else:
        while time.monotonic() - t0 < seconds:
            c.receive()  # a call per record
    report(time.process_time() - c0, c.received - n0, _switches() - w0, skipped=c.skipped)
"""
)

UR_STYLE = (
    """
import json, socket, struct, sys, time
sys.path.insert(0, sys.argv[4])
from ur_client_style import baseline_decoder
"""
    + RUSAGE
    + """
port, seconds = int(sys.argv[1]), float(sys.argv[2])
names, types = sys.argv[3].split(","), sys.argv[5].split(",")
s = socket.create_connection(("127.0.0.1", port))
def send(t, body=b""):
    s.sendall(struct.pack(">HB", 3 + len(body), t) + body)
def recv_package():
    head = b""
    while len(head) < 3: head += s.recv(3 - len(head))
    size, t = struct.unpack(">HB", head)
    body = b""
    while len(body) < size - 3: body += s.recv(size - 3 - len(body))
    return t, body
send(ord("V"), struct.pack(">H", 2)); recv_package()
send(ord("O"), struct.pack(">d", 500.0) + ",".join(names).encode()); recv_package()
send(ord("S")); recv_package()
decode = baseline_decoder(names, types)
recv_package(); ready()
t0, c0, n, w0 = time.monotonic(), time.process_time(), 0, _switches()
while time.monotonic() - t0 < seconds:
    t, body = recv_package()
    if t == ord("U"):
        state = decode(body[1:]); n += 1
report(time.process_time() - c0, n, _switches() - w0)
"""
)

HANDSHAKE = """
s = socket.create_connection(("127.0.0.1", port))
def send(t, body=b""):
    s.sendall(struct.pack(">HB", 3 + len(body), t) + body)
send(ord("V"), struct.pack(">H", 2)); s.recv(100)
send(ord("O"), struct.pack(">d", 500.0) + names.encode()); s.recv(4096)
send(ord("S")); s.recv(100)
"""  # protocol 2, outputs at 500 Hz, started: raw, for the floors

FLOOR = (
    """
import json, socket, struct, sys, time
port, seconds, names, size = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], 4 + int(sys.argv[4])
unpack = struct.Struct(">4x" + sys.argv[5]).unpack_from if len(sys.argv) > 5 else None
"""
    + RUSAGE
    + HANDSHAKE
    + """s.recv(65536); ready()
got, t0, c0, w0 = 0, time.monotonic(), time.process_time(), _switches()
if unpack is None:
    while time.monotonic() - t0 < seconds:
        got += len(s.recv(65536))  # nothing else: what a wake-up per TCP segment costs
else:
    while time.monotonic() - t0 < seconds:
        data = s.recv(65536)  # and the values of the package as one plain tuple
        got += len(data)
        values = unpack(data)
report(time.process_time() - c0, got / size, _switches() - w0)
"""
)

FLOOR_C = (
    """
import os, socket, struct, sys
port, seconds, names, binary = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[5]
size = 4 + int(sys.argv[4])
"""
    + HANDSHAKE
    + """s.recv(65536)
os.set_inheritable(s.fileno(), True)
os.execv(binary, [binary, str(s.fileno()), seconds, str(size)])  # the same process, no interpreter
"""
)


def c_floor() -> str | None:
    """`recv_floor.c` built once per run in a temporary directory; None without a C compiler."""
    global _C_FLOOR
    if _C_FLOOR is None:
        compiler = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
        _C_FLOOR = ""
        if compiler is not None:
            folder = tempfile.mkdtemp(prefix="recv-floor-")
            atexit.register(shutil.rmtree, folder, ignore_errors=True)
            out = Path(folder) / "recv_floor"
            built = subprocess.run(
                [compiler, "-O2", "-o", str(out), str(Path(__file__).with_name("recv_floor.c"))],
                capture_output=True,
                text=True,
            )
            _C_FLOOR = str(out) if built.returncode == 0 else ""
            if built.returncode:
                print(f"(the C floor row is left out: {compiler} failed: {built.stderr.strip()[:200]})")
        else:
            print("(the C floor row is left out: no C compiler on this machine)")
    return _C_FLOOR or None


_C_FLOOR: str | None = None

FLOOR_BATCHED = (
    f"BATCH = {BATCH}\n"
    + """
import json, socket, struct, sys, time
port, seconds, names, size = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], int(sys.argv[4])
"""
    + RUSAGE
    + HANDSHAKE
    + """s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVLOWAT, BATCH * (4 + size))
values = struct.Struct(">4x" + sys.argv[5])  # every value of a package, its prefix skipped
ready()
got, held, t0, c0, w0 = 0, b"", time.monotonic(), time.process_time(), _switches()
while time.monotonic() - t0 < seconds:
    data = held + s.recv(2 * BATCH * (4 + size))
    whole = len(data) // (4 + size) * (4 + size)
    newest = list(values.iter_unpack(data[:whole]))[-1]  # plain tuples: no names, no checks
    held = data[whole:]
    got += whole // (4 + size)
report(time.process_time() - c0, got, _switches() - w0)
"""
)

FLOOR_ARRAYS = (
    FLOOR_BATCHED.replace("import json,", "import numpy, re, json,")
    .replace(
        "newest = list(values.iter_unpack(data[:whole]))[-1]  # plain tuples: no names, no checks",
        "newest = numpy.frombuffer(data, dtype, whole // (4 + size))[-1]  # one view: no names, no checks",
    )
    .replace(
        "ready()\n",
        # the values' struct codes as one numpy dtype behind the 4-byte prefix
        "codes = re.findall(r'(\\d*)([a-zA-Z?])', sys.argv[5])\n"
        "dtype = numpy.dtype([('p', 'V4')] + [(f'f{i}', '>' + c, (int(n),) if n else ()) "
        "for i, (n, c) in enumerate(codes)])\n"
        "ready()\n",
        1,
    )
)  # the numpy twin of FLOOR_BATCHED: what `on_batch` does, with nothing else

UR_CLIENT = (
    """
import json, sys, time
sys.path.insert(0, sys.argv[4])  # a checkout of UR's RTDE_Python_Client_Library (not on PyPI)
import rtde.rtde as rtde
"""
    + RUSAGE
    + """
port, seconds, names = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3].split(",")
con = rtde.RTDE("127.0.0.1", port)
con.connect()
con.get_controller_version()
con.negotiate_protocol_version()
con.send_output_setup(names, frequency=500)
con.send_start()
con.receive(); ready()
t0, c0, w0 = time.monotonic(), time.process_time(), _switches()
first = con.receive().timestamp
while time.monotonic() - t0 < seconds:
    state = con.receive()  # the newest package; every package read is decoded (its DataObject)
report(time.process_time() - c0, round((state.timestamp - first) * 500), _switches() - w0)
"""
)  # UR's own examples' loop (example_control_loop.py, plot.py): `receive()` a package at a time

UR_RTDE = """
import json, sys, time
import rtde_receive
port, seconds = int(sys.argv[1]), float(sys.argv[2])
r = rtde_receive.RTDEReceiveInterface(sys.argv[3], 500.0)
time.sleep(0.2)
c0, ts0 = time.process_time(), r.getTimestamp()
time.sleep(seconds)
print(json.dumps({"cpu": time.process_time() - c0, "packages": round((r.getTimestamp() - ts0) * 500)}))
r.disconnect()
"""

LABELS = {
    "iterate": "rtde_spec RtdeClient, for record in client",
    "receive": "rtde_spec RtdeClient, receive() loop",
    "callback": "rtde_spec RtdeClient, on_data callback",
    "batched": f"rtde_spec RtdeClient(batch={BATCH}), on_data",
    "longer": f"rtde_spec RtdeClient(batch={BATCH_LONG}), on_data",
    "arrays": f"rtde_spec RtdeClient(batch={BATCH}), on_batch",
    "ur": "UR-client-style loop (recv, unpack, dict)",
    "ur_client": "UR's RTDE client (rtde.py), receive()",
    "floor": "floor: bare recv() loop, nothing decoded",
    "floor_unpack": "floor: recv() + one struct unpack",
    "floor_b": f"floor, batch={BATCH}: recv + struct tuples",
    "floor_a": f"floor, batch={BATCH}: recv + numpy view",
    "floor_c": "floor: bare recv() loop in C",
}


AGAINST = "@"  # a row key's suffix: the same row with another checkout of rtde_spec (`--against`)


HOME = str(Path(__file__).resolve().parents[1])  # the checkout these benchmarks belong to


def start(code: str, *args: str, tree: str | None = None) -> subprocess.Popen[str]:
    """A row's code in its own process, importing rtde_spec from this checkout or from `tree`
    (its directory is the child's first path entry either way: `python -c` puts the working
    directory first, so that is set too)."""
    root = tree or HOME
    return subprocess.Popen(
        [sys.executable, "-c", code, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=root,
        # numpy's import starts a BLAS thread that spins for up to ~0.1 s of CPU, sometimes inside
        # the timed window: nothing here uses BLAS (the same setting for every row)
        env={**os.environ, "PYTHONPATH": root, "OPENBLAS_NUM_THREADS": "1"},
    )


def result(proc: subprocess.Popen[str], timeout: float = 120) -> dict[str, Any]:
    out, err = proc.communicate(timeout=timeout)
    if proc.returncode:
        raise SystemExit(err)
    return json.loads(out.strip().splitlines()[-1])  # type: ignore[no-any-return]


def child(code: str, *args: str, timeout: float = 120, tree: str | None = None) -> dict[str, Any]:
    return result(start(code, *args, tree=tree), timeout)


def specs(
    port: int,
    seconds: float,
    names: list[str],
    types: list[str],
    size: int,
    fmt: str,
    ur_client: str | None = None,
) -> dict[str, Any]:
    """Each row's child code and arguments; UR's own client's row with a checkout of it."""
    joined, here, span = ",".join(names), str(Path(__file__).parent), str(seconds)
    binary = c_floor()
    in_c = {"floor_c": (FLOOR_C, str(port), span, joined, str(size), binary)} if binary else {}
    return {
        "iterate": (OURS, str(port), span, joined, "iterate"),
        "receive": (OURS, str(port), span, joined, "receive"),
        "callback": (OURS, str(port), span, joined, "callback"),
        "ur": (UR_STYLE, str(port), span, joined, here, ",".join(types)),
        "floor": (FLOOR, str(port), span, joined, str(size)),
        "floor_unpack": (FLOOR, str(port), span, joined, str(size), fmt),
        "batched": (OURS, str(port), span, joined, "callback-batched"),
        "floor_b": (FLOOR_BATCHED, str(port), span, joined, str(size), fmt),
        "longer": (OURS, str(port), span, joined, "callback-batched", str(BATCH_LONG)),
        "arrays": (OURS, str(port), span, joined, "array-batched"),
        "floor_a": (FLOOR_ARRAYS, str(port), span, joined, str(size), fmt),
        **in_c,
        **({"ur_client": (UR_CLIENT, str(port), span, joined, ur_client)} if ur_client else {}),
    }


def rounds_of(
    spec: dict[str, Any], rounds: int, against: str | None = None
) -> tuple[dict[str, list[float]], dict[str, list[float]]]:
    """CPU µs and wake-ups per package of every row in every round, rows in a rotated order.
    A row and its twin from the other checkout (`against`) run at the same time, side by side
    under the same load: their ratio is the A/B figure the drifting load moves least."""
    keys = [k for k in spec if not k.endswith(AGAINST)]
    us: dict[str, list[float]] = {k: [] for k in spec}
    wakes: dict[str, list[float]] = {k: [] for k in spec}
    for r in range(rounds):
        for key in keys[r % len(keys) :] + keys[: r % len(keys)]:
            code, *args = spec[key]
            runs = {key: start(code, *args)}
            if key + AGAINST in spec:
                runs[key + AGAINST] = start(code, *args, tree=against)
            for name, proc in runs.items():
                got = result(proc)
                us[name].append(got["cpu"] / got["packages"] * 1e6)
                wakes[name].append(got["wakeups"] / got["packages"])
    return us, wakes


def syscalls_per_package(code: str, args: list[str], window: float = 2.0) -> dict[str, float] | None:
    """System calls per package of a running loop (every thread), by `strace -c -f` attached for
    `window` seconds once the loop runs; None without strace (or where it may not attach)."""
    strace = shutil.which("strace")
    if strace is None:
        return None
    proc = start(code, *args)
    assert proc.stdout is not None
    try:
        if proc.stdout.readline().strip() != "ready":
            return None
        time.sleep(0.3)
        tids = ",".join(os.listdir(f"/proc/{proc.pid}/task"))
        handle, name = tempfile.mkstemp(suffix=".strace")
        os.close(handle)
        out = Path(name)
        tracer = subprocess.Popen([strace, "-f", "-c", "-o", str(out), "-p", tids], stderr=subprocess.DEVNULL)
        time.sleep(window)
        tracer.send_signal(signal.SIGINT)
        tracer.wait(10)
        calls: dict[str, float] = {}
        for line in out.read_text().splitlines():
            parts = line.split()
            if len(parts) >= 5 and parts[0][0].isdigit() and parts[-1] != "total":
                calls[parts[-1]] = int(parts[3])
        out.unlink(missing_ok=True)
        proc.communicate(timeout=60)
    finally:
        proc.kill()
    packages = window * RATE
    per = {name: n / packages for name, n in calls.items()}
    per["total"] = sum(calls.values()) / packages
    return per


def syscall_rows(spec: dict[str, Any]) -> None:
    """The floor's system calls per package against ours (one window each)."""
    print("\nsystem calls per package (strace -c -f, a 2 s window of the running loop; ~1000 packages):")
    for key in ("floor", "iterate", "receive", "callback", "batched", "ur"):
        code, *args = spec[key]
        per = syscalls_per_package(code, args)
        if per is None:
            print("  strace not available: not counted")
            return
        top = sorted((n for n in per if n != "total"), key=lambda n: -per[n])[:3]
        listed = ", ".join(f"{n} {per[n]:.2f}" for n in top)
        print(f"  {LABELS[key]:42s} {per['total']:5.2f}  ({listed})")


def receive_rows(
    port: int,
    seconds: float,
    rounds: int,
    names: list[str],
    types: list[str],
    size: int,
    fmt: str,
    against: str | None = None,
    ur_client: str | None = None,
) -> dict[str, bool]:
    """Every row in every round; prints the table and returns the issue-30 verdicts (against UR's
    own client when a checkout of it is given, else against the UR-style loop)."""
    spec = specs(port, seconds, names, types, size, fmt, ur_client)
    if against is not None:  # ours from another checkout, in the same rounds: an A/B in one run
        twins = ("iterate", "callback", "batched")
        ordered: dict[str, Any] = {}
        for key, row in spec.items():
            ordered[key] = row
            if key in twins:
                ordered[key + AGAINST] = row  # right after its row
        spec = ordered
        for key in twins:
            LABELS[key + AGAINST] = f"  the same, {Path(against).name}"
    load0 = os.getloadavg()
    us, wakes = rounds_of(spec, rounds, against)
    load1 = os.getloadavg()

    def med(key: str) -> float:
        return statistics.median(us[key])

    def ratio(a: str, b: str) -> float:
        return statistics.median(x / y for x, y in zip(us[a], us[b], strict=True))

    print(
        f"\nreceive loop, CPU per package ({len(names)} fields, {RATE:g} Hz, one client each, "
        f"{rounds} rounds of {seconds:g} s; load average {load0[0]:.2f} before, {load1[0]:.2f} after):"
    )
    print(f"  {'':42s} {'median':>8s} {'lowest-highest':>16s} {'wake-ups/pkg':>13s}")
    for key in spec:
        spread = f"{min(us[key]):.1f}-{max(us[key]):.1f}"
        print(f"  {LABELS[key]:42s} {med(key):6.1f} µs {spread:>16s} {statistics.median(wakes[key]):13.3f}")
    rows: tuple[tuple[str, str, str], ...] = (
        ("for record in client", "iterate", "floor"),
        ("receive() loop", "receive", "floor"),
        ("on_data per package", "callback", "floor"),
        (f"batch={BATCH}", "batched", "floor_b"),
        (f"batch={BATCH_LONG}", "longer", "floor_b"),
        (f"batch={BATCH}, on_batch", "arrays", "floor_a"),
    )
    if against is not None:
        print(f"  A/B against {against}, each pair at the same time (medians of per-pair ratios):")
        for key in ("iterate", "callback", "batched"):
            label = LABELS[key].replace("rtde_spec RtdeClient", "RtdeClient")
            print(f"    {label:30s} ours / theirs {ratio(key, key + AGAINST):.2f}x")
        rows += tuple(
            (f"{label} ({Path(against).name})", key + AGAINST, low)
            for label, key, low in rows
            if key + AGAINST in us
        )
    print("  ratios (medians of per-round ratios):")
    for label, key, low in rows:
        over = statistics.median(x - y for x, y in zip(us[key], us[low], strict=True))
        real = f"UR's client / ours {ratio('ur_client', key):5.1f}x, " if "ur_client" in us else ""
        print(
            f"    {label:28s} {real}UR style / ours {ratio('ur', key):5.1f}x, ours / floor "
            f"{ratio(key, low):5.2f}x (+{over:.1f} µs over the floor)"
        )
    peer = "ur_client" if "ur_client" in us else "ur"
    peer_name = "UR's client" if peer == "ur_client" else "UR style"
    over = statistics.median(x - y for x, y in zip(us["floor_unpack"], us["floor"], strict=True))
    print(f"    (one struct unpack, cold, in a per-package loop: +{over:.1f} µs over the bare recv() loop)")
    listed = "; ".join(f"{k} " + "/".join(f"{v:.1f}" for v in us[k]) for k in us)
    print(f"  (µs per round: {listed})")
    verdicts = {}
    for label, key, target, vs in (
        ("for record in client", "iterate", TARGET_ITER_US, TARGET_ITER_VS_UR),
        (f"batch={BATCH}", "batched", TARGET_BATCH_US, TARGET_BATCH_VS_UR),
        (f"batch={BATCH_LONG}", "longer", TARGET_BATCH_US, TARGET_BATCH_VS_UR),
        (f"batch={BATCH}, on_batch", "arrays", TARGET_BATCH_US, TARGET_BATCH_VS_UR),
    ):
        got, vs_ur = med(key), ratio(peer, key)
        verdicts[label] = hit = got <= target and vs_ur >= vs
        print(
            f"  targets (issue 30), {label}: <= {target} µs (got {got:.1f}), >= {vs}x less than {peer_name} "
            f"({vs_ur:.1f}x): {'met' if hit else 'MISSED'}"
        )
    got, vs_ur = med("batched"), ratio(peer, "batched")
    verdicts["recording"] = hit = got <= TARGET_US and vs_ur >= TARGET_VS_UR
    print(
        f"  targets (recording), batch={BATCH}: <= {TARGET_US} µs (got {got:.1f}), >= {TARGET_VS_UR}x less "
        f"than {peer_name} ({vs_ur:.1f}x): {'met' if hit else 'MISSED'}"
    )
    floor = med("floor")
    in_c = f", {med('floor_c'):.1f} µs in C" if "floor_c" in us else ""
    print(
        f"  the floor of one wake-up per package on this machine now: {floor:.1f} µs "
        f"(bare recv() loop{in_c}); "
        f"<= {TARGET_ITER_US} µs {'is' if floor <= TARGET_ITER_US else 'is NOT'} reachable waking per package"
    )
    if "floor_c" in us:
        ur = med(peer)
        print(
            f"  >= {TARGET_ITER_VS_UR}x less than {peer_name} is {ur / TARGET_ITER_VS_UR:.1f} µs a package "
            f"(the C loop waking per package: {med('floor_c'):.1f} µs); >= {TARGET_BATCH_VS_UR}x is "
            f"{ur / TARGET_BATCH_VS_UR:.1f} µs (batched recv + struct tuples: {med('floor_b'):.1f} µs)"
        )
    return verdicts


# --- warm, in one process: what our own code costs over the floor ---------------------------

WARM = """
import json, socket, struct, sys, threading, time
sys.path.insert(0, sys.argv[1])
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS as NAMES
from rtde_spec import Catalogue, RecipeCodec, RtdeClient
from rtde_spec._generated import rtde_models as gen
mode, n = sys.argv[2], int(sys.argv[3])
cat = Catalogue.builtin()
types = [cat.get(name, "output").type for name in NAMES]
codec = RecipeCodec.for_names(NAMES, "output")
package = codec.encode_package(codec.decode(bytes(codec.size)), recipe_id=1)
REPLIES = {
    "V": gen.RequestProtocolVersionReply(accepted=True).to_bytes(),
    "v": gen.GetUrcontrolVersionReply(major=5, minor=15, bugfix=0, build=0).to_bytes(),
    "O": gen.SetupOutputsV2Reply(output_recipe_id=1, variable_types=types).to_bytes(),
    "S": gen.StartReply(accepted=True).to_bytes(),
}
listener = socket.create_server(("127.0.0.1", 0))
accepted = []
def controller():  # answers the handshake, then leaves the connection to the timed loop
    conn = listener.accept()[0]
    accepted.append(conn)
    held = b""
    while True:
        while len(held) < 3 or len(held) < struct.unpack_from(">H", held)[0]:
            held += conn.recv(4096)
        size, kind = struct.unpack_from(">HB", held)
        held = held[size:]
        conn.sendall(REPLIES[chr(kind)])
        if chr(kind) == "S":
            return
thread = threading.Thread(target=controller)
thread.start()
port = listener.getsockname()[1]
if mode.startswith("floor"):
    s = socket.create_connection(("127.0.0.1", port))
    frequency = struct.pack(">d", 500.0)
    for request in (b"\\x00\\x05V\\x00\\x02", b"\\x00\\x03v", b"\\x00\\x0bO" + frequency, b"\\x00\\x03S"):
        s.sendall(request)
    thread.join()
    s.recv(65536)  # the four replies
    up, new, kind = codec.struct.unpack_from, tuple.__new__, codec.record_type
    take = (lambda: s.recv(65536)) if mode == "floor" else (lambda: new(kind, up(s.recv(65536), 4)))
else:
    c = RtdeClient("127.0.0.1", port, queue_size=100000).connect()
    c.setup_outputs(NAMES, 500.0)
    c.start()
    thread.join()
    take = c.receive if mode == "receive" else iter(c).__next__
send = accepted[0].send
for _ in range(200):
    send(package); take()
best = []
for _ in range(5):
    t0 = time.thread_time()
    for _ in range(n):
        send(package); take()
    best.append((time.thread_time() - t0) / n * 1e6)
import rtde_spec
print(json.dumps({"us": sorted(best)[2], "from": rtde_spec.__file__}))
"""


def warm_rows(rounds: int = 5, calls: int = 20000, against: str | None = None) -> None:
    """One package sent, then taken, in one process, caches warm: our code's own cost per package
    over the floor, which the load barely moves (the median of `rounds` rounds, modes in turn);
    with `against`, the same loops from that checkout too."""
    here = str(Path(__file__).parent)
    labels = {
        "floor": "floor: send + recv()",
        "floor_record": "floor: send + recv() + unpack + record",
        "iterate": "ours: send + next(iter(client))",
        "receive": "ours: send + client.receive()",
    }
    if against is not None:
        for key in ("iterate", "receive"):
            labels[key + AGAINST] = labels[key].replace("ours", Path(against).name)
    got: dict[str, list[float]] = {k: [] for k in labels}
    for _ in range(rounds):
        for key in labels:
            tree = against if key.endswith(AGAINST) else None
            got[key].append(child(WARM, here, key.rstrip(AGAINST), str(calls), tree=tree)["us"])
    print(f"\nwarm, in one process (a scripted controller on loopback sends one package, the loop takes it; "
          f"{calls} calls, median of {rounds} rounds):")  # fmt: skip
    base = got["floor_record"]
    for key, label in labels.items():
        over = statistics.median(x - y for x, y in zip(got[key], base, strict=True))
        extra = f"  ({over:+.2f} µs over the recv + record floor)" if not key.startswith("floor") else ""
        print(f"  {label:42s} {statistics.median(got[key]):6.2f} µs{extra}")


def ur_rtde_row(serve: Callable[[str, int], tuple[subprocess.Popen[str], int]], seconds: float) -> None:
    """ur_rtde's C++ receive interface against its own emulator on 127.0.0.2:30004 (its fixed port)."""
    try:
        import rtde_receive  # noqa: F401
    except ImportError:
        print("  ur_rtde: not installed (pip install ur_rtde)")
        return
    proc, port = serve("127.0.0.2", 30004)
    try:
        urr = child(UR_RTDE, str(port), str(seconds), "127.0.0.2")
    finally:
        proc.terminate()
        proc.wait(10)
    print(f"  {'ur_rtde RTDEReceiveInterface (C++)':42s} {urr['cpu'] / urr['packages'] * 1e6:6.1f} µs")
