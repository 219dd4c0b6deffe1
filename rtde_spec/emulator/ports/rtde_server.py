"""The emulator's RTDE port: one connection per client, each with its own recipes.

Follows the guides: protocol 1 until a version request is accepted (its output data
packages without the recipe id byte, as a controller sends them); NOT_FOUND and
IN_USE in setup replies; input recipe ids from 1 (0 refuses a recipe); one output
recipe per client; start refused without an output recipe; pause always accepted;
outputs every floor(base / frequency) control steps; names limited to the spec's
setup byte limit. Bad input gets a text message, or that client's disconnect when
its stream cannot be framed or it sends too many bad packages; a client is held to the
port's limits (guard.py: first package soon after connecting, no package left half
sent, bounded backlog) — never an effect on other clients.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

from rtde_spec._generated import rtde_models as gen
from rtde_spec._generated.constants import RTDE_ANSWERS, RTDE_LIMITS
from rtde_spec._generated.enums import TextMessageLevel
from rtde_spec.emulator.ports.guard import GuardedConnection, Port
from rtde_spec.errors import DecodeError, RtdeSpecError
from rtde_spec.printable import safe_text
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec
from rtde_spec.rtde.codec import decode, observe, setup_names
from rtde_spec.rtde.data_forms import sent_without_recipe_id, without_recipe_id
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.wire.framing import PackageFramer
from rtde_spec.wire.rtde_messages import RtdeMessage

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")
NOT_FOUND, IN_USE = RTDE_ANSWERS["not_found"], RTDE_ANSWERS["in_use"]
INVALID_ID = RTDE_LIMITS["invalid_recipe_id"]
MAX_PACKAGE = RTDE_LIMITS["package_max_bytes"]
MAX_INPUT_RECIPES = RTDE_LIMITS["input_recipes_max"]
SOURCE = "rtde_spec emulator"
ERROR, EXCEPTION = TextMessageLevel.ERROR_MESSAGE, TextMessageLevel.EXCEPTION_MESSAGE


class RtdeHub:
    """What the RTDE connections share: the model, input ownership, the clients."""

    def __init__(self, model: ControllerModel) -> None:
        self.model = model
        self.owners: dict[str, RtdeConnection] = {}
        self.connections: set[RtdeConnection] = set()

    def send_outputs(self, step: int) -> None:
        """Every started client whose rate divides this step gets a data package."""
        for conn in list(self.connections):
            if conn.started and conn.output is not None and step % conn.divisor == 0:
                conn.send_output()


class RtdeConnection(GuardedConnection):
    """One RTDE client: its protocol version, recipes and start state; held to the port's limits."""

    needs_handshake = True

    def __init__(self, hub: RtdeHub, port: Port) -> None:
        super().__init__(port)
        self.hub = hub
        self.state = ProtocolState()
        self.framer = PackageFramer()
        self.output: RecipeCodec | None = None
        self.output_names: tuple[str, ...] = ()
        self.bare = False  # the output's packages go without the recipe id (protocol 1 at its setup)
        self.divisor = 1
        self.inputs: dict[int, RecipeCodec] = {}
        self.started = False
        self.sent = 0

    # --- asyncio ------------------------------------------------------------

    def opened(self) -> None:
        self.hub.connections.add(self)
        log.info("RTDE client connected: %s", self.peer)

    def closed(self) -> None:
        self.started = False
        self.hub.connections.discard(self)
        for name, owner in list(self.hub.owners.items()):
            if owner is self:
                del self.hub.owners[name]  # its inputs are free for other clients again
        log.info("RTDE client gone: %s", self.peer)

    def data_received(self, data: bytes) -> None:
        if self.dropped:
            return
        try:
            packages = self.framer.feed(data)
        except DecodeError as exc:
            self._send_text(f"cannot frame the stream: {exc}", EXCEPTION)
            self.drop(f"its stream cannot be framed: {exc}")
            return
        if not self.received(self.framer.pending, len(packages)):
            return
        for _, package in packages:
            try:
                message = decode(package, protocol_version=self.state.version, sender="client")
            except RtdeSpecError as exc:
                if self.refused_message(str(exc)):
                    # the first bad package is logged; later ones only go to the client
                    self._text(f"bad package: {exc}", ERROR, logged=self.bad_messages == 1)
                    continue
                return
            try:
                self.handle(message)
            except RtdeSpecError as exc:
                self._text(f"refused: {exc}", ERROR)
            if self.dropped:
                return

    # --- the protocol -------------------------------------------------------

    def handle(self, message: RtdeMessage) -> None:
        if isinstance(message, gen.RequestProtocolVersion):
            accepted = message.protocol_version in gen.PROTOCOLS
            self._send(gen.RequestProtocolVersionReply(accepted=accepted))
            observe(self.state, message)
            self.state.on_reply(accepted)
        elif isinstance(message, gen.GetUrcontrolVersion):
            v = self.hub.model.version
            self._send(
                gen.GetUrcontrolVersionReply(
                    major=v.major, minor=v.minor, bugfix=v.bugfix, build=v.build or 0
                )
            )
        elif isinstance(message, (gen.SetupOutputsV1, gen.SetupOutputsV2)):
            frequency = getattr(message, "output_frequency", self.hub.model.base_hz)
            self._setup_outputs(message.variable_names, frequency)
        elif isinstance(message, gen.SetupInputs):
            self._setup_inputs(message.variable_names)
        elif isinstance(message, gen.Start):
            ok = self.output is not None
            if not ok:
                self._text("start refused: no valid output recipe is set up", ERROR)
            self.started = ok
            self._send(gen.StartReply(accepted=ok))
        elif isinstance(message, gen.Pause):
            self.started = False
            self._send(gen.PauseReply(accepted=True))
        elif isinstance(message, gen.DataPackage):
            self._inputs(message)
        elif isinstance(message, (gen.TextMessage, gen.TextMessageV1Client)):
            log.info("text from %s: %s", self.peer, safe_text(str(message.message)))

    def _names(self, names: list[str]) -> tuple[list[str], bool]:
        """The requested names (a trailing comma's empty name dropped), and whether they fit the limit."""
        names = setup_names(names)
        limit = self.hub.model.catalogue.setup_names_limit(self.hub.model.version)[0] or MAX_PACKAGE
        if len(",".join(names).encode()) > limit:  # the CB3 guide's 2048; e-Series takes URCL's 9,173
            self._text(f"setup refused: names exceed {limit} bytes", ERROR)
            return names, False
        return names, bool(names)

    def _setup_outputs(self, requested: list[str], frequency: float) -> None:
        names, ok = self._names(requested)
        model = self.hub.model
        types = [model.outputs[n].type if n in model.outputs else NOT_FOUND for n in names] or [NOT_FOUND]
        ok = ok and NOT_FOUND not in types
        if ok and not 0 < frequency <= model.base_hz:
            self._text(
                f"setup refused: frequency {frequency} outside (0, {model.base_hz}] Hz",
                ERROR,
            )
            ok = False
        if ok and self.started:
            self._text("setup refused while started: pause first", ERROR)
            ok = False
        if ok:
            self.output = RecipeCodec.for_names(names, "output", model.catalogue)
            self.output_names = tuple(names)
            self.bare = sent_without_recipe_id("controller", self.state.version)  # once, not per package
            self.divisor = max(1, math.floor(model.base_hz / frequency))
        if self.state.version == 1:
            self._send(gen.SetupOutputsV1Reply(variable_types=types))
        else:
            self._send(
                gen.SetupOutputsV2Reply(output_recipe_id=1 if ok else INVALID_ID, variable_types=types)
            )

    def _setup_inputs(self, requested: list[str]) -> None:
        names, ok = self._names(requested)
        model, owners = self.hub.model, self.hub.owners
        types = []
        for n in names:
            if n not in model.inputs:
                types.append(NOT_FOUND)
            elif owners.get(n, self) is not self:
                types.append(IN_USE)
            else:
                types.append(model.inputs[n].type)
        types = types or [NOT_FOUND]
        ok = ok and NOT_FOUND not in types and IN_USE not in types
        recipe_id = INVALID_ID
        if ok and len(self.inputs) >= MAX_INPUT_RECIPES:
            self._text(f"setup refused: at most {MAX_INPUT_RECIPES} input recipes", ERROR)
        elif ok:
            recipe_id = len(self.inputs) + 1
            self.inputs[recipe_id] = RecipeCodec.for_names(names, "input", model.catalogue)
            for n in names:
                owners[n] = self
        self._send(gen.SetupInputsReply(input_recipe_id=recipe_id, variable_types=types))

    def _inputs(self, message: gen.DataPackage) -> None:
        codec = self.inputs.get(message.recipe_id)
        if codec is None:
            self._text(f"data package of unknown input recipe {message.recipe_id}", ERROR)
            return
        try:
            values = codec.decode(message.payload)
        except DecodeError as exc:
            self._text(f"bad input data: {exc.relocated(PAYLOAD_OFFSET)}", ERROR)
            return
        self.hub.model.apply_inputs(values)

    # --- sending ------------------------------------------------------------

    def send_output(self) -> None:
        assert self.output is not None
        values = self.hub.model.values
        data = self.output.encode_package({n: values[n] for n in self.output_names}, recipe_id=1)
        if self.bare:
            data = without_recipe_id(data)  # protocol 1: as a controller sends it (spec: data_recipe_id)
        if self.write(data):
            self.sent += 1
        else:
            self.started = False

    def _send(self, message: RtdeMessage) -> None:
        self.write(message.to_bytes())

    def _text(self, text: str, level: TextMessageLevel, logged: bool = True) -> None:
        if logged:
            log.warning("to %s: %s", self.peer, text)
        self._send_text(text, level)

    def _send_text(self, text: str, level: TextMessageLevel) -> None:
        message: Any
        if self.state.version == 1:
            message = gen.TextMessageV1Controller(message_type=int(level), message=_ascii(text))
        else:
            message = gen.TextMessage(message=_ascii(text), source=SOURCE, warning_level=int(level))
        self._send(message)


def _ascii(text: str) -> str:
    return text.encode("ascii", "replace").decode("ascii")[:200]
