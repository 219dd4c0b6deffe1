"""Data packages against hand-packed bytes: every data-package type, both directions, every decoder."""

from __future__ import annotations

from typing import Any

import pytest
import yaml

from rtde_spec import RecipeCodec

from .helpers import DATA

CASES = yaml.safe_load((DATA / "data_golden.yaml").read_text())


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, (tuple, list)) else value


@pytest.mark.parametrize("case", CASES, ids=[f"{c['direction']}-{c['recipe_id']}" for c in CASES])
def test_data_package(case: dict[str, Any]) -> None:
    data = bytes.fromhex(case["hex"])
    codec = RecipeCodec.for_names(case["names"], case["direction"])
    values = case["values"]
    record = codec.decode_package(data, recipe_id=case["recipe_id"])
    assert {k: _plain(v) for k, v in record._asdict().items()} == values
    assert {k: _plain(v) for k, v in codec.decode(data[4:]).items()} == values
    assert codec.encode_package(values, recipe_id=case["recipe_id"]) == data
    assert codec.encode_package(record, recipe_id=case["recipe_id"], strict=True) == data
    many = codec.decode_many(data * 3, recipe_id=case["recipe_id"])
    assert len(many) == 3 and all(_plain(many[name][2].tolist()) == values[name] for name in values)
    parsed = codec.construct_struct.parse(data)  # the construct struct a user can take
    assert {name: _plain(parsed[name]) for name in values} == values
    assert codec.construct_struct.build({"recipe_id": case["recipe_id"], **values}) == data


def test_the_cases_cover_every_data_package_type_in_both_directions() -> None:
    from rtde_spec import Catalogue

    cat = Catalogue.builtin()
    for direction in ("input", "output"):
        covered = {
            cat.get(n, direction).type for c in CASES if c["direction"] == direction for n in c["names"]
        }  # type: ignore[union-attr]
        wanted = {i.type for i in cat.fields(direction) if i.wire.size}
        assert covered == wanted, (direction, wanted - covered)


def test_decode_many_names_the_first_bad_package_of_each_kind() -> None:
    case = CASES[0]
    data = bytes.fromhex(case["hex"])
    codec = RecipeCodec.for_names(case["names"], case["direction"])
    size = len(data)
    for index, (at, byte) in enumerate([(0, 0x7F), (2, ord("M")), (3, 9)]):  # size, type, recipe id
        bad = bytearray(data * 4)
        bad[size * (index + 1) + at] = byte
        with pytest.raises(Exception, match=f"package {index + 1} is not a data package") as exc:
            codec.decode_many(bytes(bad), recipe_id=1)
        assert exc.value.offset == size * (index + 1)  # type: ignore[attr-defined]
