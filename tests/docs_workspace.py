"""The example files the docs' commands name: captures, recipes, streams, a script, a scenario.

They ship in the package (`rtde_spec/examples/files/`, written by `rtde-spec examples DIR`);
this module makes them: the captures are written with dpkt (tests/capture_files.py), an
implementation independent of ours, the byte files from the package's embedded examples.
Regenerate the shipped copies with `PYTHONPATH=. python3 -m tests.docs_workspace`;
tests/test_examples.py holds them equal. One is recorded, not made: `driver.pcap`, a driver-like
client's session with the emulator captured on loopback by
`python -m rtde_spec.examples.make_driver_capture` (copied here as it ships).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from rtde_spec import RecipeCodec, build
from rtde_spec.examples import primary_stream, rtde_session
from rtde_spec.metamodel.catalogue import Catalogue

from .capture_files import Conversation, write
from .test_spec_import_write import guide_from_spec, hand_made  # a guide of a release after today's spec

NAMES = ["timestamp", "actual_q", "actual_TCP_pose", "robot_mode"]
TYPES = ["DOUBLE", "VECTOR6D", "VECTOR6D", "INT32"]

UR_CONFIG = """<?xml version="1.0"?>
<rtde_config>
  <recipe key="state">
    <field name="timestamp" type="DOUBLE"/>
    <field name="actual_q" type="VECTOR6D"/>
    <field name="robot_mode" type="INT32"/>
  </recipe>
  <recipe key="setp">
    <field name="input_double_register_0" type="DOUBLE"/>
    <field name="input_double_register_1" type="DOUBLE"/>
  </recipe>
  <recipe key="watchdog">
    <field name="input_int_register_0" type="INT32"/>
  </recipe>
</rtde_config>
"""

SCRIPT = """def move():
  movej([0, -1.57, 1.57, -1.57, -1.57, 0], a=1.4, v=1.05)
  set_standard_digital_out(0, True)
  textmsg("moved")
end
"""


def _package(codec: RecipeCodec, i: int) -> bytes:
    pose = (0.4 + i * 1e-3, 0.1, 0.3, 0.0, 3.14, 0.0)
    values = {"timestamp": i * 0.002, "actual_q": tuple(0.1 * j + i * 1e-3 for j in range(6)),
              "actual_TCP_pose": pose, "robot_mode": 7}  # fmt: skip
    return codec.encode_package(values, recipe_id=1)


def _rtde_session(conv: Conversation, codec: RecipeCodec, packages: int, setup: bool = True) -> None:
    conv.handshake()
    if setup:
        conv.send("client", build("request_protocol_version", protocol_version=2))
        conv.send("server", build("request_protocol_version_reply", accepted=True))
        conv.send("client", build("get_urcontrol_version"))
        conv.send("server", build("get_urcontrol_version_reply", major=5, minor=15, bugfix=0, build=1))
        conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=NAMES))
        conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=TYPES))
        conv.send("client", build("start"))
        conv.send("server", build("start_reply", accepted=True))
    for i in range(packages):
        conv.send("server", _package(codec, i))


def _primary(conv: Conversation) -> None:
    conv.handshake()
    stream = primary_stream()
    for start in range(0, len(stream), 500):
        conv.send("server", stream[start : start + 500], dt=0.1)


SCENARIO = """controller: 5.15.0
outputs:
  actual_q: {sine: {amplitude: 0.5, period: 4.0, offset: [0, -1.57, 1.57, 0, 0, 0]}}
  output_double_register_24: {ramp: {start: 0, rate: 0.1}}
  robot_mode: 7
"""
SHIPPED = Path(__file__).resolve().parents[1] / "rtde_spec" / "examples" / "files"
RECORDED = "driver.pcap"  # rtde_spec/examples/make_driver_capture.py records it


def make_workspace(folder: Path) -> Path:
    codec = RecipeCodec.for_names(NAMES, "output")
    rtde = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    _rtde_session(rtde, codec, 500)
    primary = Conversation(("10.0.0.2", 51001), ("10.0.0.10", 30001))
    _primary(primary)
    write(folder / "robot.pcapng", [rtde, primary], fmt="pcapng")
    (folder / "captures").mkdir()
    for k, robot in enumerate(("10.0.0.10", "10.0.0.11")):
        conv = Conversation(("10.0.0.2", 52000 + k), (robot, 30004))
        _rtde_session(conv, codec, 200)
        write(folder / "captures" / f"robot{k}.pcap", [conv])
    late = Conversation(("10.0.0.2", 53000), ("10.0.0.10", 30004))
    _rtde_session(late, codec, 100, setup=False)
    write(folder / "late.pcap", [late])
    (folder / "outputs.txt").write_text("# the output recipe\n" + "\n".join(NAMES) + "\n")
    (folder / "data.bin").write_bytes(b"".join(_package(codec, i) for i in range(100)))
    session = rtde_session()
    (folder / "session.bin").write_bytes(b"".join(p for sender, p, _ in session if sender == "client"))
    (folder / "capture_30001.bin").write_bytes(primary_stream())
    (folder / "rtde_config.xml").write_text(UR_CONFIG)
    (folder / "move.script").write_text(SCRIPT)
    (folder / "moving.yaml").write_text(SCENARIO)
    shutil.copyfile(SHIPPED / RECORDED, folder / RECORDED)  # recorded on loopback, not made here
    (folder / "rtde-guide-5.30.txt").write_text(hand_made(guide_from_spec(Catalogue.builtin().spec)))
    return folder


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as scratch:
        made = make_workspace(Path(scratch))
        for old in SHIPPED.iterdir():  # the recorded capture stays; the rest is made again
            if old.name != RECORDED:
                shutil.rmtree(old) if old.is_dir() else old.unlink()
        shutil.copytree(made, SHIPPED, dirs_exist_ok=True)
    print(f"wrote {SHIPPED}")
