"""The figure in README's Foxglove section: the emulator runs a two-movej program while
`rtde-spec record -o emulator.mcap` records it; the MCAP file is read back with the `mcap`
package's reader (not ours) and its joints and TCP position plotted.

    python3 docs/figures/emulator_mcap.py          # writes docs/figures/emulator_mcap.png
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import matplotlib

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.primary.client import PrimaryClient

PROGRAM = """def demo():
  movej([0.5, -1.2, 1.4, -1.5, -1.5, 0.3], a=1.4, v=1.0)
  movel(p[-0.35, 0.25, 0.45, 0, 3.14, 0], a=1.2, v=0.25)
  movej([-0.5, -1.8, 1.9, -1.6, -1.5, -0.3], a=1.4, v=1.0)
end
"""


def main() -> None:
    here = Path(__file__).resolve().parent
    emu = EmulatorThread(EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0)).start()

    def move() -> None:
        time.sleep(1.5)  # the recorder is connected by then
        with PrimaryClient("127.0.0.1", emu.ports["primary"]) as robot:
            robot.send_script(PROGRAM)
            time.sleep(0.3)

    with tempfile.TemporaryDirectory() as tmp:
        mcap_file = Path(tmp) / "emulator.mcap"
        threading.Thread(target=move, daemon=True).start()
        subprocess.run(
            [sys.executable, "-m", "rtde_spec", "record", "--host", "127.0.0.1",
             "--port", str(emu.ports["rtde"]), "--fields", "timestamp,actual_q,actual_TCP_pose",
             "--duration", "9", "-o", str(mcap_file)],
            check=True,
        )  # fmt: skip
        emu.stop()
        from mcap.reader import make_reader

        t, q, tcp = [], [], []
        with open(mcap_file, "rb") as f:
            for _, _, message in make_reader(f).iter_messages(topics=["/rtde/outputs/1"]):
                row = json.loads(message.data)
                t.append(message.log_time / 1e9)
                q.append(row["actual_q"])
                tcp.append(row["actual_TCP_pose"])
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [x - t[0] for x in t]
    fig, (joints, pose) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for j in range(6):
        joints.plot(t, [r[j] for r in q], label=f"actual_q[{j}]")
    joints.set_ylabel("rad")
    joints.legend(ncol=3, fontsize=8)
    joints.set_title("/rtde/outputs/1 of emulator.mcap (rtde-spec record, read with mcap's reader)")
    for j, name in enumerate("xyz"):
        pose.plot(t, [r[j] for r in tcp], label=f"actual_TCP_pose.{name}")
    pose.set_ylabel("m")
    pose.set_xlabel("log time [s]")
    pose.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(here / "emulator_mcap.png", dpi=100)
    print(here / "emulator_mcap.png", len(t), "messages")


if __name__ == "__main__":
    main()
