"""The ROS driver's side of external control, played by a test client written from
spec/external_control/: the emulator runs an external-control style program (threads, named
sockets, a reverse socket read with time-outs, servoj from a thread each control step) sent to
the primary port; the client serves the reverse port, streams servoj targets as URCL's
ReverseInterface does (8 big-endian int32 words: timeout, six targets x 1,000,000, mode), and
sees the arm follow, then stops the program with the STOPPED mode. The ports are the machine's
free ones rather than 50001, so runs in parallel do not collide.
"""

from __future__ import annotations

import socket
import time

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.emulator.controller.model import HOME_Q
from rtde_spec.external.codec import record_codec
from rtde_spec.primary.codec import PrimaryStreamDecoder

PROGRAM = """def external_control():
  global cmd_q = get_actual_joint_positions()
  global mode = -1
  global steptime = get_steptime()
  thread servo_thread():
    while True:
      if mode == 1:
        servoj(cmd_q, t=steptime, lookahead_time=0.03, gain=2000)
      else:
        sync()
      end
    end
  end
  if not socket_open("127.0.0.1", {port}, "reverse_socket"):
    popup("no driver", error=True)
    halt
  end
  socket_send_string("hello driver", "reverse_socket")
  servo = run servo_thread()
  timeout = 1.0
  while mode != -2:
    params = socket_read_binary_integer(8, "reverse_socket", timeout)
    if params[0] > 0:
      timeout = params[1] / 1000
      q = [params[2], params[3], params[4], params[5], params[6], params[7]]
      i = 0
      while i < 6:
        q[i] = q[i] / 1000000.0
        i = i + 1
      end
      enter_critical
      cmd_q = q
      mode = params[8]
      exit_critical
    else:
      textmsg("reverse read timed out")
      mode = -2
    end
  end
  kill servo
  textmsg("external control stopped")
  socket_close("reverse_socket")
end
"""


def robot_messages_until(
    primary: socket.socket, text: str, seconds: float = 5.0
) -> tuple[list[str], list[str]]:
    """The text messages and runtime exceptions a primary client reads, until `text` comes (the
    port drains the controller's events every 100 ms: a client reads them, as a driver does)."""
    decoder, texts, errors = PrimaryStreamDecoder(), list[str](), list[str]()
    deadline = time.monotonic() + seconds
    primary.settimeout(0.5)
    while text not in texts and time.monotonic() < deadline:
        try:
            chunk = primary.recv(65536)
        except TimeoutError:
            continue
        if not chunk:
            break
        for _, message in decoder.feed(chunk):
            if getattr(message, "text_message", None) is not None:
                texts.append(str(message.text_message))
            if getattr(message, "runtime_exception_text_message", None) is not None:
                errors.append(str(message.runtime_exception_text_message))
    return texts, errors


def test_the_arm_follows_servoj_targets_streamed_on_the_reverse_port() -> None:
    codec = record_codec("reverse", "reverse_command")
    target = [q + 0.15 for q in HOME_Q]
    with socket.create_server(("127.0.0.1", 0)) as reverse_server:
        port = reverse_server.getsockname()[1]
        config = EmulatorConfig(
            rtde_port=None, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
        )
        with EmulatorThread(config) as emu:
            watcher = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
            with socket.create_connection(("127.0.0.1", emu.ports["primary"])) as primary:
                primary.sendall(PROGRAM.format(port=port).encode())
            reverse_server.settimeout(10)
            robot, _ = reverse_server.accept()
            with robot:
                robot.settimeout(5)
                assert robot.recv(64) == b"hello driver"
                steps = 250
                for i in range(steps + 1):  # 0.5 s at 500 Hz, a straight ramp to the target
                    q = [h + (t - h) * i / steps for h, t in zip(HOME_Q, target, strict=True)]
                    robot.sendall(
                        codec.encode("motion_target", {"read_timeout": 2.0, "target": q, "control_mode": 1})
                    )
                    time.sleep(0.002)
                deadline = time.monotonic() + 5
                while emu.call(lambda: list(emu.model.values["actual_q"])) != pytest.approx(target, abs=1e-5):
                    robot.sendall(
                        codec.encode(
                            "motion_target", {"read_timeout": 2.0, "target": target, "control_mode": 1}
                        )
                    )
                    time.sleep(0.01)
                    assert time.monotonic() < deadline, "the arm did not follow"
                stop = {"read_timeout": 2.0, "target": [0.0] * 6, "control_mode": -2}
                robot.sendall(codec.encode("motion_target", stop))
                deadline = time.monotonic() + 5
                while emu.call(lambda: emu.model.program) is not None:
                    assert time.monotonic() < deadline, "the program did not stop"
                    time.sleep(0.01)
                assert robot.recv(64) == b""  # the program closed its socket
            with watcher:
                texts, errors = robot_messages_until(watcher, "external control stopped")
    assert "external control stopped" in texts
    assert not errors
    assert emu.model.values["actual_q"] == pytest.approx(target, abs=1e-5)
