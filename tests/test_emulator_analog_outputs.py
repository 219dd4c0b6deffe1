"""The standard analog outputs as a controller shows them, on every port that carries them.

Each output has a level and a domain. The level is what URScript's set_standard_analog_out(n, f)
or RTDE's standard_analog_output_0/1 set: the fraction of the output's range (1.0 is 10 V or
20 mA, the Script manual says). The domain is 0 current (4-20 mA) or 1 voltage (0-10 V), set by
URScript's set_analog_outputdomain(port, domain), which PolyScope's program preamble calls from
the installation, or by RTDE's standard_analog_output_type for the outputs its mask selects; a
default installation has both in current. RTDE shows the domain in bits 2-3 of analog_io_types,
the primary Robot State in the masterboard's analog output domains: the same on both, whoever
set it. Which unit the level comes back in (A or mA, or the fraction) is not settled by UR's
documents, so the emulator keeps the fraction (docs/decisions.md).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec._generated.enums import AnalogIoTypes
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.ports.script import run_script

from .ur_rtde_robot import Clients, serve, settle_until

UR_RTDE_HOST = "127.0.0.77"  # ur_rtde's ports are fixed: a loopback address of this module's own
pytestmark = pytest.mark.fixed_ports(UR_RTDE_HOST)
OUT0_V, OUT1_V = int(AnalogIoTypes.ANALOG_OUTPUT_0_VOLTAGE), int(AnalogIoTypes.ANALOG_OUTPUT_1_VOLTAGE)
OUTPUT_BITS = OUT0_V | OUT1_V
# the preamble PolyScope writes for an installation with output 0 in volts, output 1 in current
PREAMBLE = """def prog():
  set_analog_outputdomain(0, 1)
  set_analog_outputdomain(1, 0)
  set_standard_analog_out(0, 0.4)
  set_standard_analog_out(1, 0.75)
end
"""


@pytest.mark.parametrize("version", ["3.15.8", "5.15.0"])
def test_both_outputs_start_in_current_as_a_default_installation_has_them(version: str) -> None:
    model = ControllerModel(version)
    assert model.values["analog_io_types"] & OUTPUT_BITS == 0
    assert (model.values["standard_analog_output0"], model.values["standard_analog_output1"]) == (0.0, 0.0)


@pytest.mark.parametrize("version", ["3.0.0", "3.15.8", "5.15.0"])
def test_set_analog_outputdomain_sets_the_domain_and_leaves_the_level(version: str) -> None:
    model = ControllerModel(version)  # 3.0.0: no RTDE yet, the masterboard data carries it
    assert run_script(model, PREAMBLE) == [line.strip() for line in PREAMBLE.splitlines()[1:5]]
    assert model.values["analog_io_types"] & OUTPUT_BITS == OUT0_V
    assert (model.values["standard_analog_output0"], model.values["standard_analog_output1"]) == (0.4, 0.75)
    run_script(model, "set_analog_outputdomain(0, 0)\nset_analog_outputdomain(1, 1)")
    assert model.values["analog_io_types"] & OUTPUT_BITS == OUT1_V
    assert (model.values["standard_analog_output0"], model.values["standard_analog_output1"]) == (0.4, 0.75)
    run_script(model, "set_analog_outputdomain(port=1, domain=0)")
    assert model.values["analog_io_types"] & OUTPUT_BITS == 0


@pytest.mark.parametrize(
    "line",
    [
        "set_analog_outputdomain(2, 1)",  # two analog outputs
        "set_analog_outputdomain(0, 2)",  # 0 current, 1 voltage
        "set_analog_outputdomain(0, 0.5)",
        "set_analog_outputdomain(0, True)",
        "set_analog_outputdomain(0)",
    ],
)
def test_a_domain_call_a_controller_would_refuse_changes_nothing(line: str) -> None:
    model = ControllerModel("5.15.0")
    before = dict(model.values)
    assert run_script(model, line) == [] and model.values == before


def test_an_rtde_output_type_overrides_what_the_program_set() -> None:
    model = ControllerModel("5.15.0")
    run_script(model, PREAMBLE)
    model.apply_inputs(
        {
            "standard_analog_output_mask": 0b10,
            "standard_analog_output_type": 0b10,
            "standard_analog_output_1": 0.5,
        }
    )  # output 1 only: output 0 keeps its domain and level
    assert model.values["analog_io_types"] & OUTPUT_BITS == OUT0_V | OUT1_V
    assert (model.values["standard_analog_output0"], model.values["standard_analog_output1"]) == (0.4, 0.5)


# --- over loopback, with clients ---------------------------------------------------------


def _until(read: Callable[[], Any], done: Callable[[Any], bool], what: str, pause: float = 0.02) -> Any:
    """`read()` until `done` says yes, within 3 s; an RTDE read waits for its record (pause 0), so
    the records (oldest first, at 10 Hz) are read faster than they come."""
    deadline = time.monotonic() + 3.0
    while True:
        value = read()
        if done(value):
            return value
        assert time.monotonic() < deadline, f"{what}: last seen {value!r}"
        time.sleep(pause)


def _masterboard(host: str, port: int) -> Any:
    """The masterboard data of the next Robot State on a primary/secondary port."""
    with PrimaryClient(host, port, timeout=5) as client:
        state: Any = next(m for m in client if m.NAME == "robot_state")
    return state["masterboard_data"]


def _shown(board: Any) -> tuple[int, int, float, float]:
    return (
        board.analog_output_domain0,
        board.analog_output_domain1,
        board.analog_output0,
        board.analog_output1,
    )


@pytest.fixture
def emulator() -> Iterator[EmulatorThread]:
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        realtime_port=None,
        dashboard_port=None,
        controller="5.15.0",
    )
    emu = EmulatorThread(config).start()
    try:
        yield emu
    finally:
        emu.stop()


def test_rtde_and_the_robot_state_show_the_domain_a_program_or_an_rtde_client_set(
    emulator: EmulatorThread,
) -> None:
    host, ports = "127.0.0.1", emulator.ports
    fields = ["analog_io_types", "standard_analog_output0", "standard_analog_output1"]
    with RtdeClient(host, ports["rtde"]) as rtde:
        rtde.setup_outputs(fields, 10)
        inputs = rtde.setup_inputs(
            ["standard_analog_output_mask", "standard_analog_output_type", "standard_analog_output_0"]
        )
        rtde.start()

        def outputs() -> tuple[int, float, float]:
            record = rtde.receive()
            return (
                record.analog_io_types & OUTPUT_BITS,
                record.standard_analog_output0,
                record.standard_analog_output1,
            )

        assert outputs() == (0, 0.0, 0.0)
        assert _shown(_masterboard(host, ports["secondary"])) == (0, 0, 0.0, 0.0)
        with PrimaryClient(host, ports["primary"]) as client:
            client.send_script(PREAMBLE)
        _until(outputs, lambda v: v == (OUT0_V, 0.4, 0.75), "RTDE after the program", pause=0)
        _until(lambda: _shown(_masterboard(host, ports["secondary"])), lambda v: v == (1, 0, 0.4, 0.75),
               "the Robot State after the program")  # fmt: skip
        # ur_rtde's setAnalogOutputCurrent(0, 0.2): output 0's mask, its type bit clear, the level
        rtde.send(
            inputs, standard_analog_output_mask=1, standard_analog_output_type=0, standard_analog_output_0=0.2
        )
        _until(outputs, lambda v: v == (0, 0.2, 0.75), "RTDE after the RTDE input", pause=0)
        _until(lambda: _shown(_masterboard(host, ports["primary"])), lambda v: v == (0, 0, 0.2, 0.75),
               "the Robot State after the RTDE input")  # fmt: skip


# --- ur_rtde (pip), on a controller's own ports ------------------------------------------


@pytest.mark.parametrize("controller", ["5.15.0", "3.15.8"])
def test_ur_rtde_sees_the_levels_and_domains_its_calls_and_a_script_set(controller: str) -> None:
    pytest.importorskip("rtde_io", reason="ur_rtde is installed by the test extra")
    host = UR_RTDE_HOST
    proc, log = serve(host, controller, "UR5e" if controller.startswith("5.") else "UR5")
    clients = Clients()
    try:
        clients.new("recv", "rtde_receive", "RTDEReceiveInterface", host)
        clients.new("io", "rtde_io", "RTDEIOInterface", host)
        major, minor = (int(p) for p in controller.split(".")[:2])
        clients.new("script", "script_client", "ScriptClient", host, major, minor)
        clients.call("script", "connect")
        with RtdeClient(host, 30004) as rtde:
            rtde.setup_outputs(["analog_io_types"], 10)
            rtde.start()

            def domains() -> int:
                return int(rtde.receive().analog_io_types) & OUTPUT_BITS

            assert domains() == 0  # both in current, as a default installation
            assert clients.call("script", "sendScriptCommand", "set_analog_outputdomain(1, 1)\n")
            _until(domains, lambda v: v == OUT1_V, "analog_io_types after ur_rtde's script", pause=0)
            assert _masterboard(host, 30002).analog_output_domain1 == 1
            assert clients.call("io", "setAnalogOutputVoltage", 0, 0.3)
            settle_until(
                lambda: clients.call("recv", "getStandardAnalogOutput0") == 0.3, 3.0, "output 0's level"
            )
            _until(
                domains,
                lambda v: v == OUT0_V | OUT1_V,
                "analog_io_types after setAnalogOutputVoltage",
                pause=0,
            )
            assert clients.call("io", "setAnalogOutputCurrent", 1, 0.25)  # the type bit clears the script's
            settle_until(
                lambda: clients.call("recv", "getStandardAnalogOutput1") == 0.25, 3.0, "output 1's level"
            )
            _until(domains, lambda v: v == OUT0_V, "analog_io_types after setAnalogOutputCurrent", pause=0)
            assert _shown(_masterboard(host, 30001)) == (1, 0, 0.3, 0.25)
        for name in ("recv", "io", "script"):
            clients.call(name, "disconnect")
    finally:
        clients.close()
        proc.terminate()
        proc.wait(10)
    assert not [line for line in log if "Traceback" in line], log
