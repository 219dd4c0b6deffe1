"""A stream of data packages of several recipes, decoded with the codec of one.

A client's stream holds several input recipes (UR's own example: setp and watchdog). Decoded
with one codec, the packages of another recipe of the same size came out as wrong numbers
(an INT32 pair read as the DOUBLE 2.1e-314), without a word.
"""

from __future__ import annotations

import pytest

from rtde_spec import RecipeCodec
from rtde_spec.errors import DecodeError
from rtde_spec.rtde.stream import Batch, Package, StreamDecoder

SETP = RecipeCodec.for_names(["input_double_register_24"], "input")  # 8 bytes
PAIR = RecipeCodec.for_names(["input_int_register_25", "input_int_register_26"], "input")  # 8 bytes too


def setp(i: int) -> bytes:
    return SETP.encode_package({"input_double_register_24": i + 0.5}, 2)


PAIR_PACKAGE = PAIR.encode_package({"input_int_register_25": 1, "input_int_register_26": 2}, 3)


def items(decoder: StreamDecoder, *chunks: bytes) -> list[Package | Batch]:
    return [item for chunk in chunks for item in decoder.feed(chunk)]


def setp_values(found: list[Package | Batch]) -> list[float]:
    out: list[float] = []
    for item in found:
        if isinstance(item, Batch):
            out += [float(v) for v in item.array["input_double_register_24"]]
        elif item.values is not None:
            out.append(item.values["input_double_register_24"])
    return out


@pytest.mark.parametrize("batch", [True, False])
def test_the_recipe_chosen_is_decoded_and_the_others_pass_undecoded(batch: bool) -> None:
    decoder = StreamDecoder("client", protocol_version=2, codec=SETP, batch=batch, recipe_id=2)
    stream = b"".join([setp(0), setp(1), PAIR_PACKAGE, setp(2), setp(3), PAIR_PACKAGE])
    found = items(decoder, stream[:30], stream[30:])
    assert setp_values(found) == [0.5, 1.5, 2.5, 3.5]
    others = [i for i in found if isinstance(i, Package) and i.values is None]
    assert [p.message.recipe_id for p in others] == [3, 3]  # type: ignore[attr-defined]
    assert decoder.packages == 6


@pytest.mark.parametrize("batch", [True, False])
def test_without_a_choice_a_second_recipe_is_an_error_after_the_first_recipe_s_packages(batch: bool) -> None:
    decoder = StreamDecoder("client", protocol_version=2, codec=SETP, batch=batch)
    found: list[Package | Batch] = []
    with pytest.raises(DecodeError, match="a data package of recipe 3 after those of recipe 2") as raised:
        for item in decoder.feed(setp(0) + setp(1) + PAIR_PACKAGE + setp(2)):
            found.append(item)
    assert setp_values(found) == [0.5, 1.5]  # those before it are kept
    assert raised.value.offset == 2 * len(setp(0)) + 3  # the recipe id byte of the third package


def test_without_a_choice_skip_errors_skips_and_counts_the_other_recipe() -> None:
    decoder = StreamDecoder("client", protocol_version=2, codec=SETP, skip_errors=True)
    found = items(decoder, setp(0) + PAIR_PACKAGE + setp(1) + setp(2))
    assert setp_values(found) == [0.5, 1.5, 2.5]
    assert decoder.skipped.count == 1
