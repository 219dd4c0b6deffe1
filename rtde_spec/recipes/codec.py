"""Data packages of one recipe, compiled once from the spec's types.

Per recipe: one `struct.Struct`, one generated function that regroups the flat
unpacked tuple into named values, a NamedTuple record type, a pydantic model and
a numpy dtype. Per package: one `unpack_from` and one call — nothing is looked
up, nothing validated twice.
"""

from __future__ import annotations

import difflib
import keyword
import struct
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import (
    BYTE_ORDER,
    DATA_PACKAGE_PREFIX_FIELDS,
    DATA_PACKAGE_PREFIX_OFFSETS,
    DATA_PACKAGE_TYPE,
    RTDE_LIMITS,
)
from rtde_spec.errors import DecodeError, RecipeError, require
from rtde_spec.metamodel.catalogue import Catalogue, Direction, FieldInfo, WireTypeInfo
from rtde_spec.recipes.encoding import PREFIX, Encoder, RecipeItem, expected_recipe_id, install
from rtde_spec.recipes.record import record_class

if TYPE_CHECKING:
    from pydantic import BaseModel

_PREFIX, _PREFIX_FIELDS = PREFIX, DATA_PACKAGE_PREFIX_FIELDS  # header + recipe id; their names
_SIZE_AT, _TYPE_AT, _RECIPE_ID_AT = DATA_PACKAGE_PREFIX_OFFSETS
PAYLOAD_OFFSET = _PREFIX.size
_new_tuple = tuple.__new__
_PY = {"int": int, "float": float, "bool": bool, "str": str}


def _py_type(wire: WireTypeInfo) -> Any:
    """The plain Python type of a wire type, for the record's annotations (no bounds)."""
    one = _PY[wire.kind]
    return one if wire.count == 1 else tuple.__class_getitem__((one,) * wire.count)


def _identifier(name: str) -> str:
    if not name.isidentifier() or keyword.iskeyword(name):
        raise RecipeError(f"{name!r} is not usable as a record field name", field=name)
    return name


class RecipeCodec:
    """Decode and encode data packages for one ordered list of variables."""

    def __init__(self, items: Sequence[tuple[str, WireTypeInfo, FieldInfo | None]]) -> None:
        if not items:
            raise RecipeError("a recipe needs at least one variable")
        layout: list[RecipeItem] = []
        offset = 0
        fmt = BYTE_ORDER
        for name, wire, info in items:
            if wire.size is None:
                raise RecipeError(f"type {wire.name} cannot be in a data package", field=name)
            layout.append(RecipeItem(_identifier(name), wire, offset, info))
            offset += wire.size
            fmt += wire.struct
        names = [item.name for item in layout]
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise RecipeError("a name appears twice in the recipe", field=dup)
        self.items = tuple(layout)
        self.names = tuple(names)
        self.struct = struct.Struct(fmt)
        self.size = self.struct.size
        self.package_size = PAYLOAD_OFFSET + self.size
        # whole packages, back to back: the prefix alone, and the values without it
        self._prefixes = struct.Struct(_PREFIX.format + f"{self.size}x")
        self._packages = struct.Struct(BYTE_ORDER + f"{PAYLOAD_OFFSET}x" + fmt[len(BYTE_ORDER) :])
        if self.package_size > RTDE_LIMITS["package_max_bytes"]:
            raise RecipeError(
                "data package too large for the size field",
                expected=f"<= {RTDE_LIMITS['package_max_bytes']} bytes",
                actual=f"{self.package_size} bytes",
            )
        self.record_type = record_class([(i.name, i.wire.count, _py_type(i.wire)) for i in layout])
        self._to_dict = self._compile()
        self._encoder = Encoder(self.items, self.struct, self.package_size)
        # the methods below, as one generated function each (a frame less per call on the hot path)
        encoder = self._encoder
        install(self, RecipeCodec, encode=encoder.encode, encode_package=encoder.encode_package)
        self._model_type: type[BaseModel] | None = None
        self._dtype: Any = None

    # --- construction -------------------------------------------------------

    @classmethod
    def for_names(
        cls, names: Sequence[str], direction: Direction, catalogue: Catalogue | None = None
    ) -> RecipeCodec:
        """A codec for variable names, typed from the spec's catalogue."""
        cat = catalogue or Catalogue.default()
        items = []
        for name in names:
            info = cat.get(name, direction)
            if info is None:
                close = ", ".join(difflib.get_close_matches(name, cat.names(direction), n=3, cutoff=0.6))
                hint = f" (did you mean {close}?)" if close else ""
                lists = f"; `rtde-spec fields --direction {direction}` lists them"
                raise RecipeError(f"unknown {direction} field {name!r}{hint}{lists}", field=name)
            items.append((name, info.wire, info))
        return cls(items)

    @classmethod
    def for_types(
        cls, names: Sequence[str], types: Sequence[str], catalogue: Catalogue | None = None
    ) -> RecipeCodec:
        """A codec from a setup request's names and the reply's type names."""
        cat = catalogue or Catalogue.default()
        if len(names) != len(types):
            raise RecipeError(
                "setup reply lists a different number of types than names were requested",
                expected=len(names),
                actual=len(types),
            )
        items = []
        for name, type_name in zip(names, types, strict=True):
            wire = cat.wire_types.get(type_name)
            if wire is None:
                raise RecipeError(f"type {type_name!r} has no data layout", field=name)
            items.append((name, wire, cat.get(name, "output") or cat.get(name, "input")))
        return cls(items)

    def _compile(self) -> Callable[..., Any]:
        """Generate the dict-making function once, specialised to this layout."""
        parts = []
        pos = 0
        for item in self.items:
            count = item.wire.count
            parts.append(f"t[{pos}]" if count == 1 else f"t[{pos}:{pos + count}]")
            pos += count
        pairs = ", ".join(f"{item.name!r}: {part}" for item, part in zip(self.items, parts, strict=True))
        return eval(f"lambda t: {{{pairs}}}", {})  # type: ignore[no-any-return]

    # --- decoding -----------------------------------------------------------

    def _check(self, payload: bytes | bytearray | memoryview, offset: int) -> None:
        """Offsets count from the start of the bytes given: inside them or at their end."""
        if not 0 <= offset <= len(payload):  # -4 read the last 4 bytes (struct counts from the end)
            raise DecodeError("offset outside the bytes given", expected=f"0..{len(payload)}", actual=offset)
        got = len(payload) - offset
        if got == self.size:
            return
        short = got < self.size
        where = next((i for i in self.items if i.offset + (i.wire.size or 0) > got), None) if short else None
        raise DecodeError(
            "data package payload is shorter than its recipe"
            if short
            else "data package payload is longer than its recipe",
            package="data_package",
            field=where.name if where else None,
            offset=min(offset + (where.offset if where else self.size), len(payload)),
            expected=f"{self.size} payload bytes",
            actual=f"{got} payload bytes",
        )

    def decode(self, payload: bytes | bytearray | memoryview, offset: int = 0) -> dict[str, Any]:
        """Values by name (vectors as tuples) from a payload starting at `offset`."""
        if len(payload) - offset != self.size or offset < 0:
            self._check(payload, offset)
        return self._to_dict(self.struct.unpack_from(payload, offset))  # type: ignore[no-any-return]

    def decode_record(self, payload: bytes | bytearray | memoryview, offset: int = 0) -> Any:
        """A record: every value decoded, attribute access by the spec's names; the cheapest form."""
        if len(payload) - offset != self.size or offset < 0:
            self._check(payload, offset)
        return _new_tuple(self.record_type, self.struct.unpack_from(payload, offset))

    def decode_model(self, payload: bytes | bytearray | memoryview, offset: int = 0) -> BaseModel:
        """A pydantic model of the recipe.

        model_validate, not model_construct: for 58 fields pydantic-core validates
        faster than model_construct's Python loop (benchmarks/bench_recipe_decode.py).
        """
        return self.model_type.model_validate(self.decode(payload, offset))

    def _package_prefix(self, data: bytes | bytearray | memoryview, recipe_id: int | None) -> None:
        if len(data) < PAYLOAD_OFFSET:
            raise DecodeError(
                "too short for a data package header",
                offset=len(data),
                expected=f"{PAYLOAD_OFFSET} bytes",
                actual=f"{len(data)} bytes",
            )
        size, ptype, rid = _PREFIX.unpack_from(data)
        if ptype != DATA_PACKAGE_TYPE:
            raise DecodeError(
                "not a data package",
                field="type",
                offset=_TYPE_AT,
                expected=DATA_PACKAGE_TYPE,
                actual=ptype,
            )
        if size != len(data):
            raise DecodeError(
                "size field disagrees with the package length",
                field="size",
                offset=_SIZE_AT,
                expected=len(data),
                actual=size,
            )
        if recipe_id is not None and rid != recipe_id:
            expected_recipe_id(recipe_id)  # one no package carries is said as such
            raise DecodeError(
                "data package of another recipe",
                package="data_package",
                field="recipe_id",
                offset=_RECIPE_ID_AT,
                expected=recipe_id,
                actual=rid,
            )

    def decode_package(self, data: bytes | bytearray | memoryview, recipe_id: int | None = None) -> Any:
        """A whole data package (header included) to a record; checks type, size and id."""
        self._package_prefix(data, recipe_id)
        return self.decode_record(data, PAYLOAD_OFFSET)

    def decode_records(self, data: bytes | bytearray | memoryview, recipe_id: int | None = None) -> list[Any]:
        """Whole data packages back to back -> a record each, every one in one C loop.

        What a client reading many packages per wake-up calls: the per-package Python
        step of `decode_package` is most of its cost. Every prefix is checked (size,
        type, recipe id if given); a bad package is named with its stream offset.
        """
        size = self.package_size
        self._whole_packages(len(data))
        seen = set(self._prefixes.iter_unpack(data))
        if (
            seen
            and seen != {(size, DATA_PACKAGE_TYPE, recipe_id)}
            and (recipe_id is not None or {p[:2] for p in seen} != {(size, DATA_PACKAGE_TYPE)})
        ):
            for k, at in enumerate(range(0, len(data), size)):
                try:
                    self._package_prefix(data[at : at + size], recipe_id)
                except DecodeError as exc:
                    raise exc.in_stream(at, k) from None
        return self._framed_records(data)

    def _framed_records(self, data: bytes | bytearray | memoryview) -> list[Any]:
        """`decode_records` for packages a framer has already checked (size and type of each):
        the client's read path, where the check would be done twice."""
        record_type = self.record_type
        return [_new_tuple(record_type, values) for values in self._packages.iter_unpack(data)]

    # --- encoding -----------------------------------------------------------

    def encode(self, values: Mapping[str, Any] | BaseModel | tuple[Any, ...], strict: bool = False) -> bytes:
        """The payload from a dict, a record or a model; EncodeError names a bad field.

        A vector is a list, a tuple, a 1-D numpy array or another sequence, never a
        dict, set, string or bytes. strict: BOOL takes only bool, integers only int,
        DOUBLE only int or float (a bool is not a number; NaN and infinities are
        doubles); otherwise numbers are taken as `struct` takes them (numpy scalars,
        Fraction, Decimal), 0/1 and numpy bools pass for BOOL, integral floats for
        integers. Both modes check ranges, at the same speed order: the checks are
        compiled into the one-call path for lists and tuples of builtin numbers
        (benchmarks/bench_recipe_encode.py).
        """
        return self._encoder.encode(values, strict)  # type: ignore[no-any-return]

    def encode_package(
        self,
        values: Mapping[str, Any] | BaseModel | tuple[Any, ...],
        recipe_id: int,
        strict: bool = False,
    ) -> bytes:
        """A whole data package: header, recipe id, payload; one `struct` call on the happy path."""
        return self._encoder.encode_package(values, recipe_id, strict)  # type: ignore[no-any-return]

    # --- typed views --------------------------------------------------------

    @property
    def model_type(self) -> type[BaseModel]:
        """A pydantic model with one bounded field per variable (built on first use)."""
        if self._model_type is None:
            from pydantic import ConfigDict, create_model

            from rtde_spec._generated.rtde_types import WIRE_TYPES

            fields: dict[str, Any] = {i.name: (WIRE_TYPES[i.wire.name], ...) for i in self.items}
            nan = ConfigDict(ser_json_inf_nan="strings")  # NaN as "NaN": JSON that reads back
            self._model_type = create_model("RecipeRecord", __config__=nan, **fields)
        return self._model_type

    @property
    def construct_struct(self) -> Any:
        """A construct Struct of a whole data package of this recipe (header, recipe id, fields).

        The readable definition, for parsing captures with construct directly; the
        codec's own methods are the fast path. Building fills in the size.
        """
        from rtde_spec.recipes.construct_view import recipe_construct

        return recipe_construct(self.items, self.package_size)

    @property
    def dtype(self) -> Any:
        """numpy structured dtype of a whole data package (big-endian, vectors as (n,))."""
        if self._dtype is None:
            np = require("numpy", "numpy", "numpy views of data packages")

            codes = _PREFIX.format[1:]
            fields: list[tuple[Any, ...]] = [
                (n, BYTE_ORDER + c) for n, c in zip(_PREFIX_FIELDS, codes, strict=True)
            ]
            for item in self.items:
                code = BYTE_ORDER + item.wire.struct[-1]
                fields.append(
                    (item.name, code) if item.wire.count == 1 else (item.name, code, (item.wire.count,))
                )
            self._dtype = np.dtype(fields)
            assert self._dtype.itemsize == self.package_size
        return self._dtype

    def decode_many(self, buffer: bytes | bytearray | memoryview | Any, recipe_id: int | None = None) -> Any:
        """Many same-recipe data packages -> a numpy structured array, without a copy.

        `buffer`: the packages back to back, or a 2-D numpy uint8 array with one package
        per row (rows may be spaced, as in a view of a capture file). Every package's
        size, type and recipe id are checked in one pass, and the first bad one is named.
        """
        np = require("numpy", "numpy", "decode_many")
        recipe_id = None if recipe_id is None else expected_recipe_id(recipe_id)
        size = self.package_size
        if isinstance(buffer, np.ndarray) and buffer.ndim == 2:
            if buffer.dtype != np.uint8 or buffer.shape[1] != size:
                raise DecodeError(
                    "rows are not this recipe's data packages",
                    expected=f"uint8 rows of {size} bytes",
                    actual=f"{buffer.dtype} rows of {buffer.shape[1]}",
                )
            rows = buffer if buffer.strides[1] == 1 else np.ascontiguousarray(buffer)  # e.g. a transpose
            stride = rows.strides[0]
        else:
            self._whole_packages(len(buffer))
            rows, stride = np.frombuffer(buffer, dtype=np.uint8).reshape(-1, size), size
        arr = rows.view(self.dtype)[:, 0] if len(rows) else np.zeros(0, dtype=self.dtype)
        bad = self._bad_prefixes(np, rows, recipe_id)
        if bad.any():
            index = int(np.argmax(bad))
            row = arr[index]
            raise DecodeError(
                f"package {index} is not a data package of this recipe "
                f"(size {int(row['size'])}, type {int(row['type'])}, recipe {int(row['recipe_id'])})",
                package="data_package",
                offset=index * stride,
                expected=f"size {size}, type {DATA_PACKAGE_TYPE}"
                + (f", recipe {recipe_id}" if recipe_id is not None else ""),
            )
        return arr

    def _whole_packages(self, length: int) -> None:
        """DecodeError unless `length` bytes are a whole number of this recipe's packages."""
        size = self.package_size
        if length % size:
            raise DecodeError(
                "not a whole number of this recipe's data packages",
                offset=length - length % size,
                expected=f"a multiple of {size} bytes",
                actual=f"{length} bytes",
            )

    def _bad_prefixes(self, np: Any, rows: Any, recipe_id: int | None) -> Any:
        """Which packages' size, type or recipe id is wrong: one comparison over a strided view."""
        if not len(rows):
            return np.zeros(0, dtype=bool)
        if _PREFIX_WORD is None:  # a prefix of no machine-word size: field by field
            arr = rows.view(self.dtype)[:, 0]
            bad = (arr["size"] != self.package_size) | (arr["type"] != DATA_PACKAGE_TYPE)
            return bad | (arr["recipe_id"] != recipe_id) if recipe_id is not None else bad
        dtype, mask = _PREFIX_WORD
        words = rows[:, : _PREFIX.size].view(dtype)[:, 0]
        want = int.from_bytes(_PREFIX.pack(self.package_size, DATA_PACKAGE_TYPE, recipe_id or 0), "big")
        return words != want if recipe_id is not None else (words & mask) != want


def _prefix_word() -> tuple[str, int] | None:
    """numpy dtype and mask of the whole prefix (size, type, recipe id) read as one integer."""
    widths = {1: "u1", 2: "u2", 4: "u4", 8: "u8"}
    if _PREFIX.size not in widths:
        return None
    recipe_bits = 8 * struct.calcsize(BYTE_ORDER + _PREFIX.format[-1])
    mask = ((1 << (8 * _PREFIX.size)) - 1) ^ ((1 << recipe_bits) - 1)
    return BYTE_ORDER + widths[_PREFIX.size], mask


_PREFIX_WORD = _prefix_word()
