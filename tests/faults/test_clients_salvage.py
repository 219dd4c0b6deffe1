"""Packages framed before an unusable size field, in the same read, reach the client."""

from __future__ import annotations

import pytest

from rtde_spec import DecodeError, RecipeCodec, build
from rtde_spec.rtde.client_protocol import ClientProtocol, DataRun

NAMES = ["timestamp", "robot_mode"]
TEXT = build("text_message", message="hi", source="x", warning_level=2)


def _core() -> ClientProtocol:
    core = ClientProtocol()
    core.request_protocol_version(2)
    core.receive(build("request_protocol_version_reply", accepted=True))
    core.setup_outputs(NAMES, 125.0)
    core.receive(build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=["DOUBLE", "INT32"]))
    return core


@pytest.mark.parametrize("bad", [b"\x00\x01\x78", b"\x00\x00\x55"])
def test_packages_before_a_size_below_the_header_are_handed_over(bad: bytes) -> None:
    core = _core()
    codec = RecipeCodec.for_names(NAMES, "output")
    good = b"".join(codec.encode_package({"timestamp": t, "robot_mode": 7}, recipe_id=1) for t in (1.0, 2.0))
    start = core.framer.offset  # the stream offset of this read's first byte
    with pytest.raises(DecodeError) as caught:
        core.receive(good + TEXT + bad)  # two data packages, a text message, a bad size
    assert caught.value.offset == start + len(good) + len(TEXT)  # where the bad size stands
    runs = [e for e in core.before_error if isinstance(e, DataRun)]
    assert [r.timestamp for run in runs for r in run.records] == [1.0, 2.0]
    assert len(core.before_error) == 2  # the run of both data packages, then the text message
