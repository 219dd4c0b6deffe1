"""The 2048-byte setup limit is the CB3 guide's: e-Series takes URCL-sized setups (issue 27, item 6).

UR's C++ client library sets up 406 output names in 9,173 bytes against current URSim
5.x simulators. Every output field this spec has on 5.23 (404 names, 9,133 bytes) is the
nearest list of real names: `validate`, the client's offline check and the emulator's
RTDE port take it on e-Series and refuse it on CB3.
"""

from __future__ import annotations

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.errors import RecipeError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.recipes.model import Recipe
from rtde_spec.recipes.validation import validate_recipe

from .test_cli import cli


def every_output(version: str) -> list[str]:
    cat = Catalogue.default()
    info = (cat.get(name, "output") for name in cat.names("output"))
    return [i.name for i in info if i is not None and cat.available(i, version)]


NAMES = every_output("5.23.0")


def test_the_list_is_urcl_sized() -> None:
    assert len(NAMES) == len(set(NAMES)) >= 400
    assert 9000 < len(",".join(NAMES).encode()) and len(",".join(NAMES)) > 4 * 2048


@pytest.mark.parametrize(("version", "valid"), [("5.23.0", True), ("10.11.0", True), ("3.15.8", False)])
def test_validate_holds_only_cb3_to_2048_bytes(version: str, valid: bool) -> None:
    names = [n for n in NAMES if n in every_output(version)] if version.startswith("3.") else NAMES
    assert len(",".join(names)) > 2048
    report = validate_recipe(Recipe(tuple(names), direction="output"), controller=version)
    codes = {p.code for p in report.problems}
    assert ("names-too-long" not in codes) is valid
    assert report.valid is valid


def test_validate_command_on_e_series(tmp_path: pytest.TempPathFactory) -> None:
    path = tmp_path / "urcl.txt"  # type: ignore[operator]
    path.write_text("\n".join(NAMES) + "\n")
    ok = cli("validate", str(path), "--controller", "5.23.0")
    assert ok.returncode == 0, ok.stdout + ok.stderr
    refused = cli("validate", str(path), "--controller", "3.15.8")
    assert refused.returncode != 0 and "2048" in refused.stdout + refused.stderr


def _rtde_only(controller: str) -> EmulatorThread:
    """An emulator of `controller` serving RTDE alone, on a free port."""
    config = EmulatorConfig(
        rtde_port=0, primary_port=None, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    config.controller = controller
    return EmulatorThread(config).start()


def test_emulator_on_e_series_takes_the_whole_list_and_sends_it() -> None:
    emu = _rtde_only("5.23.0")
    try:
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
            codec = client.setup_outputs(NAMES, 125)
            assert codec.names == tuple(NAMES)
            client.start()
            record = client.receive()
            assert record._fields == tuple(NAMES) and record.timestamp >= 0
    finally:
        emu.stop()


def test_client_refuses_it_for_cb3_before_sending() -> None:
    emu = _rtde_only("3.15.8")
    try:
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
            names = [n for n in NAMES if n in every_output("3.15.8")]
            with pytest.raises(RecipeError, match="2048"):
                client.setup_outputs(names, 125)
    finally:
        emu.stop()
