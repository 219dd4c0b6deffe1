"""A CB3 on 3.14 as UR's own client library finds it: URCL's CI runs every example on URSim
3.14.3 with recipes holding `tcp_offset` (an output) and the tool digital outputs (inputs), and
its external-control program calls `tool_contact` and, from 3.14.1, `ft_rtde_input_enable`.
Before, the emulator refused all four on a CB3 (the guides date them for the e-Series only), so
no URCL example started on an emulated 3.14 (spec/rtde/fields.yaml and
spec/urscript/functions.yaml, source `urcl-ci`)."""

from __future__ import annotations

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.errors import RecipeError

HOST = "127.0.0.1"
# parts of URCL's examples/resources/rtde_output_recipe.txt and rtde_input_recipe.txt
URCL_OUTPUTS = ["timestamp", "actual_q", "tcp_offset"]
URCL_INPUTS = ["tool_digital_output_mask", "tool_digital_output"]


def _emulator(version: str) -> EmulatorThread:
    config = EmulatorConfig(
        host=HOST,
        rtde_port=0,
        primary_port=None,
        secondary_port=None,
        realtime_port=None,
        dashboard_port=None,
        controller=version,
    )
    return EmulatorThread(config)


def test_a_cb3_3_14_3_takes_urcl_s_recipes() -> None:
    with _emulator("3.14.3") as emu, RtdeClient(HOST, emu.ports["rtde"]) as client:
        assert str(client.controller_version).startswith("3.14.3")
        client.setup_outputs(URCL_OUTPUTS, 125)
        client.setup_inputs(URCL_INPUTS)
        client.start()
        record = next(iter(client))
        assert len(record.tcp_offset) == 6


@pytest.mark.parametrize("names", [["tcp_offset"], ["tool_digital_output_mask"]])
def test_an_older_cb3_still_refuses_them(names: list[str]) -> None:
    with _emulator("3.14.2") as emu, RtdeClient(HOST, emu.ports["rtde"]) as client:
        with pytest.raises(RecipeError, match=names[0]):
            if names[0] == "tcp_offset":
                client.setup_outputs(["timestamp", *names], 125)
            else:
                client.setup_inputs(names)


@pytest.mark.parametrize(
    ("version", "call", "refused"),
    [
        ("3.14.3", "tool_contact(direction=[0, 0, 1, 0, 0, 0])", False),
        ("3.14.1", "ft_rtde_input_enable(False)", False),
        ("3.14.0", "ft_rtde_input_enable(False)", True),  # URCL calls enable_external_ft_sensor there
        ("3.14.0", "enable_external_ft_sensor(False)", False),
        ("5.3.0", "tool_contact(direction=[0, 0, 1, 0, 0, 0])", True),
    ],
)
def test_urcl_s_program_calls_compile_on_the_versions_it_sends_them_to(
    version: str, call: str, refused: bool
) -> None:
    model = ControllerModel(version)
    statement = f"x = {call}" if "contact" in call else call  # tool_contact returns a number
    model.run_script(f"def prog():\n  {statement}\nend")
    name = call.split("(")[0]
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert (("runtime_exception", f"compile_error_name_not_found:{name}:") in events) is refused
