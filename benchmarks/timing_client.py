"""A light RTDE client process that times when each data package arrives against its timestamp.

The emulator benchmarks start several (`python -c TIMING HOST PORT SECONDS NAMES`) so the
figure is the emulator's, not a heavy client's: raw sockets, no package of ours imported.
It prints one JSON line: packages, missed steps, p99 and max lateness in ms.
"""

TIMING = """
import json, socket, struct, sys, time
host, port, seconds, names = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
s = socket.create_connection((host, port))
s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
def send(t, body=b""):
    s.sendall(struct.pack(">HB", 3 + len(body), t) + body)
buf = b""
def package():
    global buf
    while len(buf) < 3 or len(buf) < struct.unpack_from(">H", buf)[0]:
        buf += s.recv(65536)
    size = struct.unpack_from(">H", buf)[0]
    p, buf = buf[:size], buf[size:]
    return p
send(ord("V"), struct.pack(">H", 2)); package()
send(ord("O"), struct.pack(">d", 500.0) + names.encode()); package()
send(ord("S")); package()
stamps = []
end = time.monotonic() + seconds
while time.monotonic() < end:
    p = package()
    if p[2] == ord("U"):
        stamps.append((time.perf_counter(), struct.unpack_from(">d", p, 4)[0]))
a0, t0 = stamps[0]
late = sorted(max(0.0, (a - a0) - (t - t0)) for a, t in stamps)
steps = [round((b[1] - a[1]) * 500) for a, b in zip(stamps, stamps[1:])]
print(json.dumps({"packages": len(stamps), "missed": sum(x - 1 for x in steps if x > 1),
                  "p99_ms": late[int(len(late) * 0.99)] * 1000, "max_ms": late[-1] * 1000}))
"""
