"""The XML-RPC request a program's `rpc_factory` handle sends: an int goes as <i4>.

XML-RPC allows <i4> and <int>; UR's RPC page in the Script manual names the xmlrpc-c library,
whose serializer writes <i4>, and UnderAutomation's Universal Robots SDK (PyPI
underautomation_universalrobots 9.4.0.1, its XML-RPC server: robot.xml_rpc.xml_rpc_server_request)
reads only <i4>: for the <int> the emulator sent, the argument came as "XML element type is not
supported" although its documentation's example passes an int (12) from the robot. A real HTTP
server on loopback records the bytes; no third-party package is needed.
"""

from __future__ import annotations

import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, HTTPServer

from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread

ANSWER = b"<?xml version='1.0'?>\n<methodResponse><params><param><value><i4>7</i4></value></param></params>"
ANSWER += b"</methodResponse>\n"


def test_an_int_argument_goes_as_i4_and_the_rest_as_before() -> None:
    bodies: list[bytes] = []

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:
            bodies.append(self.rfile.read(int(self.headers["Content-Length"])))
            self.send_response(200)
            self.send_header("Content-Type", "text/xml")
            self.send_header("Content-Length", str(len(ANSWER)))
            self.end_headers()
            self.wfile.write(ANSWER)

        def log_message(self, *args: object) -> None:
            pass

    server = HTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    config = EmulatorConfig(
        rtde_port=None, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    program = (
        "def rpc_test():\n"
        f'  h = rpc_factory("xmlrpc", "http://127.0.0.1:{server.server_port}/RPC2")\n'
        '  r = h.get_answer("Hello", True, 12, 12.2, p[0.1, 0.2, 0.3, 0, 0, 0], [12, 1.5])\n'
        "  global answer = r\n"
        "end\n"
    )
    try:
        with EmulatorThread(config) as emu:
            with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as sock:
                sock.sendall(program.encode())
                deadline = time.monotonic() + 5
                while not bodies and time.monotonic() < deadline:
                    time.sleep(0.05)
    finally:
        server.shutdown()
        server.server_close()
    assert len(bodies) == 1
    body = bodies[0].decode()
    assert "<methodName>get_answer</methodName>" in body
    assert "<int>" not in body
    assert body.count("<i4>12</i4>") == 2  # the argument and the list's first element
    assert "<boolean>1</boolean>" in body and "<double>12.2</double>" in body
    assert "<string>Hello</string>" in body and "<name>rx</name>" in body
