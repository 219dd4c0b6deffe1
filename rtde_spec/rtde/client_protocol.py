"""The RTDE client as a sans-I/O state machine: requests out as bytes, bytes in as events.

The blocking and asyncio clients both drive this one core, so the protocol (version
negotiation, recipes, the data path) is written once. Recipes are validated
offline against the controller's version before they are sent. Data packages of
the output recipe skip the generic codec: those that arrive back to back in one read
are cut out together and become records in one C loop (`RecipeCodec.decode_records`).

Replies are matched to requests by package type (a reply carries its request's
letter), never by arrival order: a reply nobody asked for is logged and dropped,
so one extra reply from a misbehaving peer cannot shift every later answer.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any, NamedTuple

from rtde_spec._generated.constants import (
    DATA_PACKAGE_TYPE,
    RTDE_ANSWERS,
    RTDE_LIMITS,
    RTDE_PACKAGES,
)
from rtde_spec.errors import (
    DecodeError,
    ProtocolError,
    RecipeError,
    RtdeConnectionError,
    RtdeSpecError,
    UsageError,
)
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.versions import Version
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec
from rtde_spec.recipes.encoding import PREFIX, as_mapping
from rtde_spec.recipes.model import Recipe, checked_frequency, recipe_names
from rtde_spec.rtde.client_events import DataRun, Event, InputRecipe, Reply, Request, Text
from rtde_spec.rtde.data_forms import implied_recipe_id, lacks_recipe_id, with_recipe_id
from rtde_spec.rtde.packages import (
    CONTROLLER_VERSION_REPLY,
    DATA,
    TEXTS,
    TYPE_OF,
    VERSION_REPLY,
    VERSION_REQUEST,
    Package,
    decode_package,
    encode_package,
    observe_package,
)
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.wire.framing import PackageFramer

INVALID_ID = RTDE_LIMITS["invalid_recipe_id"]
READ_SIZE = 65536  # bytes a read asks for at least: all the socket holds, in one call
UNSOLICITED_LOGGED = 10  # unsolicited replies logged one by one; after that only counted
log = logging.getLogger("rtde_spec.client")


class RecordsPath(NamedTuple):
    """The output recipe's packages as a reader takes them on its shortest path: a read that is
    exactly one package (`size` bytes beginning with `lead`, while `ClientProtocol.aligned`; its
    size added to `taken`) is `new(record_type, unpack(read, PAYLOAD_OFFSET))`; a read of several
    (`take(read, size, lead)` frames them) is `map(partial(new, record_type), many(read))`."""

    size: int  # bytes per package
    lead: bytes  # size, type and recipe id: the first bytes of each
    take: Callable[[bytes, int, bytes], int]  # the framer's: how many whole packages, 0 if not only those
    unpack: Callable[[Any, int], tuple[Any, ...]]
    many: Callable[[Any], Iterator[tuple[Any, ...]]]
    record_type: type


class ClientProtocol:
    def __init__(self, catalogue: Catalogue | None = None) -> None:
        self.catalogue = catalogue or Catalogue.default()
        self.state = ProtocolState()
        self.framer = PackageFramer()
        self.controller_version: Version | None = None
        self.output: RecipeCodec | None = None
        self.output_recipe_id: int | None = None
        self._run: tuple[int, bytes] | None = None  # (size, leading bytes) of the output's packages
        # (implied recipe id, payload size) where the output's packages may come without their id
        self._without_id: tuple[int, int] | None = None
        self.inputs: dict[int, InputRecipe] = {}
        # requests awaiting their reply, oldest first (appended by the caller's thread, removed
        # by the reader's: list copy, append and remove are each atomic)
        self._pending: list[Request] = []
        self.last_request: Request | None = None  # the request whose bytes were built last
        self.unsolicited = 0  # replies that answered no waiting request (logged, dropped)
        self.before_error: list[Event] = []  # see receive()
        self._want_records = True  # see want_records
        # the output recipe's shortest path, records wanted or not (raw bytes, numpy batches)
        self.output_path: RecordsPath | None = None
        # what a reader needs to make records of reads of whole output packages without events
        # (None before the output recipe is set up, or when nobody wants records): an attribute,
        # read once per read
        self.records_path: RecordsPath | None = None
        # A reader may take a read that is one whole data package of the output recipe itself
        # (lead bytes and size checked) while `aligned` (the framer holds nothing), adding its
        # size to `taken`; the framer counts those bytes before it is fed again.
        self.aligned = True
        self.taken = 0

    # --- requests -----------------------------------------------------------

    def request_protocol_version(self, version: int) -> bytes:
        return self._ask(VERSION_REQUEST, {"protocol_version": version})

    def get_controller_version(self) -> bytes:
        return self._ask("get_urcontrol_version", {})

    def setup_outputs(self, names: Sequence[str] | str, frequency: float) -> bytes:
        """Validate offline (names, direction, version, rate), then the setup request."""
        names = recipe_names(names)
        hz = checked_frequency(frequency, required=True)
        self._validate(names, "output", hz)
        if self.state.version == 1:
            return self._ask("setup_outputs_v1", {"variable_names": list(names)}, ("output", names))
        values = {"output_frequency": hz, "variable_names": list(names)}
        return self._ask("setup_outputs_v2", values, ("output", names))

    def setup_inputs(self, names: Sequence[str] | str) -> bytes:
        names = recipe_names(names)
        self._validate(names, "input", None)
        return self._ask("setup_inputs", {"variable_names": list(names)}, ("input", names))

    def start(self) -> bytes:
        return self._ask("start", {})

    def pause(self) -> bytes:
        return self._ask("pause", {})

    def _ask(
        self, name: str, values: dict[str, Any], setup: tuple[str, tuple[str, ...]] | None = None
    ) -> bytes:
        """The request's bytes; its reply is awaited from now on (`last_request`).

        Built by the layout engine from values this core checked (recipes are validated
        offline first), without the pydantic models: a recorder starts sooner.
        """
        data = encode_package(name, values)
        request = Request(name, TYPE_OF[name], Package(name, TYPE_OF[name], values), setup)
        self._pending.append(request)
        self.last_request = request
        return data

    def forget(self, request: Request) -> None:
        """Stop waiting for `request`'s reply (it timed out): a late one is then unsolicited."""
        try:
            self._pending.remove(request)
        except ValueError:
            pass  # answered meanwhile

    def no_reply(self, request: Request, waited: float, where: str) -> Exception:
        """The error of a request left without its reply: naming what came instead, if anything."""
        self.forget(request)
        if request.others:
            reply = RTDE_PACKAGES.get((request.package_type, "controller", self.state.version))
            return ProtocolError(
                f"requested {request.name}, got {', '.join(request.others)} instead of its reply "
                f"(none within {waited} s)",
                subject=where,
                expected=reply or request.name + " reply",
                actual=request.others[0],
            )
        return TimeoutError(f"no reply to {request.name} from {where} within {waited} s")

    def closed(self, where: str, cause: str = "the controller closed the connection") -> RtdeSpecError:
        """The error that ends a connection; a DecodeError when it ended inside a package, whose
        bytes are lost (so iterating clients raise it instead of ending quietly)."""
        if self.taken:
            self.framer.passed(self.taken)
            self.taken = 0
        held = self.framer.pending
        if not held:
            return RtdeConnectionError(cause, subject=where)
        try:
            self.framer.close()
        except DecodeError as exc:
            return DecodeError(
                f"connection closed inside a package: {held} of {exc.expected} ({cause})",
                subject=where,
                offset=exc.offset,
                expected=exc.expected,
                actual=exc.actual,
            )
        return RtdeConnectionError(cause, subject=where)

    def send_inputs(self, recipe: InputRecipe, values: Any, named: Mapping[str, Any]) -> bytes:
        """One input data package: `values` (a dict, record, model, dataclass or pandas row) and
        the values `named`, the latter winning; the codec names whatever is wrong."""
        if not isinstance(recipe, InputRecipe):
            raise UsageError(
                f"send takes the InputRecipe that setup_inputs returned, not a {type(recipe).__name__}"
            )
        if self.inputs.get(recipe.recipe_id) is not recipe:  # the controller logs it, writes nothing
            raise UsageError(f"input recipe {recipe.recipe_id} was set up by another client, not this one")
        if values is None:
            values = named
        elif named:
            values = {**as_mapping(values), **named}
        return recipe.codec.encode_package(values, recipe.recipe_id)

    def text_message(self, text: str, level: int, source: str = "rtde_spec") -> bytes:
        from rtde_spec.rtde.codec import message_by_name  # the model checks the user's text

        name = "text_message_v1_client" if self.state.version == 1 else "text_message"
        return message_by_name(name)(message=text, source=source, warning_level=level).to_bytes()

    def _validate(self, names: Sequence[str], direction: str, frequency: float | None) -> None:
        from rtde_spec.recipes.validation import validate_recipes

        controller = str(self.controller_version) if self.controller_version else None
        recipe = Recipe(tuple(names), direction=direction)  # type: ignore[arg-type]
        report = validate_recipes(
            [recipe], controller=controller, frequency=frequency, catalogue=self.catalogue
        )
        errors = [p for p in report.all_problems if p.severity == "error"]
        if errors:
            listed = "; ".join(f"{p.field or 'recipe'}: {p.message}" for p in errors)
            where = f" on controller {controller}" if controller else ""
            raise RecipeError(f"{direction} recipe refused before sending{where}: {listed}")

    # --- incoming -------------------------------------------------------------

    def receive(self, data: bytes) -> list[Event]:
        """Events for every package this data completes. A package that does not decode or
        breaks the protocol raises its error; the events of the packages before it in this
        data are then in `before_error`."""
        if self.taken:
            self.framer.passed(self.taken)
            self.taken = 0
        try:
            return self._receive(data)
        finally:
            self.aligned = not self.framer.pending

    def _receive(self, data: bytes) -> list[Event]:
        output, run = self.output, self._run
        if output is not None and run is not None:
            wanted = self._want_records
            if len(data) == run[0]:  # the usual read at one package per wake-up
                if self.framer.take_run(data, *run):
                    one = [output.decode_record(data, PAYLOAD_OFFSET)] if wanted else []
                    return [DataRun(one, data, run[0])]
            elif len(data) % run[0] == 0 and not self.framer.pending:  # a batch of whole packages
                # decoded first, checked after: the read's bytes come into the cache once (a
                # batch's bytes are cold after the wait); bad leads drop the records, below
                records = output._framed_records(data) if wanted else []
                if self.framer.take_run(data, *run):
                    return [DataRun(records, data, run[0])]
        events: list[Event] = []
        try:
            try:
                packages = self.framer.feed(data, run)
            except RtdeSpecError:  # an unusable size: the packages before it still count
                self._events(self.framer.salvaged, events)
                raise
            self._events(packages, events)
        except RtdeSpecError:
            self.before_error = events  # the packages before the fault: handed out, not dropped
            raise
        return events

    @property
    def want_records(self) -> bool:
        """False when only raw bytes are taken (a recorder decoding its batches with numpy):
        data packages are framed and checked, and no record is made."""
        return self._want_records

    @want_records.setter
    def want_records(self, wanted: bool) -> None:
        self._want_records = wanted
        self.records_path = self.output_path if wanted else None

    def one_record(self, data: bytes) -> Any:
        """The record of a read that is exactly one data package of the output recipe (what a
        caller reading at one package per wake-up gets), framed; None for any other read, which
        then goes to `receive`. The shortest path from a read to a record: no event, no list."""
        run = self._run
        if (
            run is not None
            and len(data) == run[0]
            and self._want_records
            and self.aligned
            and data.startswith(run[1])
        ):
            self.taken += run[0]
            return self.output.decode_record(data, PAYLOAD_OFFSET)  # type: ignore[union-attr]
        return None

    def _events(self, packages: list[tuple[int, Any]], events: list[Event]) -> None:
        """Append the event of each framed package (a fault raises, `events` keeps those before).

        The output recipe is read per package: a setup reply earlier in the same read sets it,
        and the data after it (a pipelined setup and start) are of that recipe."""
        for _, package in packages:
            output, run, without_id = self.output, self._run, self._without_id
            if without_id is not None and lacks_recipe_id(package, without_id[1]):
                package = with_recipe_id(package, without_id[0])  # protocol 1: read by its size
            if output is not None and run is not None and package[: len(run[1])] == run[1]:
                records = output.decode_records(package) if self._want_records else []
                events.append(DataRun(records, package, run[0]))
                continue
            message = decode_package(package, protocol_version=self.state.version, sender="controller")
            event = self._control(message)
            if event is not None:
                events.append(event)

    def _control(self, message: Package) -> Event | None:
        name, values = message.name, message.values
        if name in TEXTS:
            level = values.get("warning_level", values.get("message_type", 3))
            return Text(level, values["message"], values.get("source", "controller"))
        if name == DATA:
            output = self.output
            if output is not None and message.recipe_id == self.output_recipe_id:
                raise DecodeError(
                    "data package of the output recipe, of another size than the recipe's",
                    package=DATA,
                    field="payload",
                    expected=f"{output.package_size - PAYLOAD_OFFSET} bytes",
                    actual=f"{len(message.payload)} bytes",
                )
            raise ProtocolError(
                "data package of no recipe this client set up",
                package=DATA,
                field="recipe_id",
                expected="no data before setup_outputs" if output is None else self.output_recipe_id,
                actual=message.recipe_id,
            )
        request = self._match(message)
        if request is None:
            return None
        if name == VERSION_REPLY:
            observe_package(self.state, request.name, request.message.values)  # the version it answers
            observe_package(self.state, name, values)
        elif name == CONTROLLER_VERSION_REPLY:
            self.controller_version = Version(
                values["major"], values["minor"], values["bugfix"], values["build"]
            )
        elif request.setup is not None:
            try:
                self._setup_reply(message, *request.setup)
            except RtdeSpecError as exc:
                return Reply(message, exc, request)
        return Reply(message, None, request)

    def _match(self, message: Package) -> Request | None:
        """The oldest waiting request this reply answers (same package type), now answered;
        None for a reply nobody asked for, which is logged and changes nothing."""
        waiting = list(self._pending)
        for request in waiting:
            if request.package_type == message.package_type:
                self.forget(request)
                return request
        for request in waiting:
            request.others.append(message.name)
        self.unsolicited += 1
        if self.unsolicited <= UNSOLICITED_LOGGED:
            asked = ", ".join(r.name for r in waiting) or "nothing"
            log.warning("ignored a %s nobody asked for (waiting for: %s)", message.name, asked)
        return None

    def _setup_reply(self, message: Package, direction: str, names: tuple[str, ...]) -> None:
        types: list[str] = list(message.values["variable_types"])
        recipe_id = message.values.get(f"{direction}_recipe_id", 1)  # protocol 1: one output recipe
        refused = [f"{n}: {t}" for n, t in zip(names, types, strict=False) if t in RTDE_ANSWERS.values()]
        if refused or recipe_id == INVALID_ID:
            reason = ", ".join(refused) or "the controller refused the recipe"
            raise RecipeError(f"{direction} recipe refused by the controller: {reason}")
        if len(types) != len(names):  # a reply for another request, or broken: never read half of it
            raise RecipeError(
                f"{direction} setup reply lists {len(types)} types for the {len(names)} names requested",
                expected=len(names),
                actual=len(types),
            )
        codec = RecipeCodec.for_types(list(names), types, self.catalogue)
        if direction == "output":
            self.output, self.output_recipe_id = codec, recipe_id
            # size, type and recipe id: a package of another recipe is never read as this one
            lead = PREFIX.pack(codec.package_size, DATA_PACKAGE_TYPE, recipe_id)
            self._run = (codec.package_size, lead)
            self.output_path = RecordsPath(
                codec.package_size,
                lead,
                self.framer.take_run,
                codec.struct.unpack_from,
                codec._packages.iter_unpack,
                codec.record_type,
            )
            self.records_path = self.output_path if self._want_records else None
            implied = implied_recipe_id("controller", self.state.version)
            self._without_id = (recipe_id, codec.size) if implied == recipe_id else None
        else:
            self.inputs[recipe_id] = InputRecipe(recipe_id, tuple(names), codec)
