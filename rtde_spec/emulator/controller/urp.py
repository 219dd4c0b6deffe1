"""PolyScope programs (.urp) as the URScript a controller runs for them.

A `.urp` is the program tree PolyScope saves (XML, gzip-compressed by e-Series PolyScope);
PolyScope turns it into URScript when it plays it and saves that beside it as `.script`.
Programs shared as examples (UR's own RTDE client's `rtde_control_loop.urp`, programs in
repositories) often come without the `.script`: the emulator's dashboard `load` translates
the tree here, as PolyScope would: the before-start sequence, the threads started, the
main program looped unless it runs once; every assignment is to a program (global)
variable. Expressions are the characters PolyScope stores, with its operator glyphs
(`≟`, `≠`, ...) written as URScript's, and variables by the node they reference (XStream's
relative paths, resolved here).

Nodes read: Assignment, Script (line or file), If / ElseIf / Else, Loop (forever, while,
counted), Move (MoveJ, MoveL, MoveP) with fixed or variable waypoints, Wait (time or
expression), Set (a digital output), Comment, Folder, Halt, Popup, SubProgram and Call,
Thread, and the External Control URCap's node (the ROS driver's program, asked of the driver
when the program is played: external_program.py). Any other node is a `UrpError` naming it
and where it is: a program the emulator cannot run as PolyScope would is refused, never run in
part.
"""

from __future__ import annotations

import re
import zlib
from xml.etree import ElementTree

from rtde_spec.emulator.controller.external_program import EXTERNAL_CONTROL, HEADER_MARK, NODE_MARK

MAX_XML_BYTES = 16 << 20  # a program tree past this is refused (a gzip bomb stops here)
GLYPHS = {
    "≟": "==",
    "≠": "!=",
    "≤": "<=",
    "≥": ">=",
    "−": "-",
    "·": "*",
    "÷": "/",
    "∧": " and ",
    "∨": " or ",
    "¬": "not ",
}
_STEP = re.compile(r"^(?P<tag>[\w.-]+)(?:\[(?P<index>\d+)\])?$")
_NAME = re.compile(r"^[A-Za-z_]\w*$")


class UrpError(ValueError):
    """A .urp the emulator cannot translate: what and where (the node's path in the tree)."""


def read_urp(data: bytes) -> ElementTree.Element:
    """The program tree of a .urp file's bytes (plain or gzip-compressed XML)."""
    if data[:2] == b"\x1f\x8b":
        inflate = zlib.decompressobj(wbits=31)
        try:
            data = inflate.decompress(data, MAX_XML_BYTES + 1)
        except zlib.error as exc:
            raise UrpError(f"not a gzip-compressed program: {exc}") from None
        if len(data) > MAX_XML_BYTES:
            raise UrpError(f"the program tree is over {MAX_XML_BYTES} bytes uncompressed")
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as exc:
        raise UrpError(f"not a PolyScope program: {exc}") from None
    if root.tag != "URProgram":
        raise UrpError(f"not a PolyScope program: its root is <{root.tag}>, not <URProgram>")
    return root


def urp_to_script(data: bytes, fallback_name: str = "program") -> str:
    """URScript for a .urp file's bytes: one `def`, as in the `.script` PolyScope saves."""
    root = read_urp(data)
    return _Translator(root).program(root, root.get("name") or fallback_name)


class _Translator:
    def __init__(self, root: ElementTree.Element) -> None:
        self.parents = {child: parent for parent in root.iter() for child in parent}
        self.lines: list[str] = []
        self.depth = 1
        self.loops = 0
        self.external = False  # an External Control node (the ROS driver's URCap) is in the tree

    # --- the tree ------------------------------------------------------------

    def program(self, root: ElementTree.Element, name: str) -> str:
        top = _children(root)
        ident = _identifier(name)
        self.lines.append(f"def {ident}():")
        known = {
            "SpecialSequence",
            "SubProgram",
            "Thread",
            "MainProgram",
            "Installation",
            "InitVariablesNode",
        }
        for node in top:
            if node.tag not in known:
                raise UrpError(f"<{node.tag}> at the program's top is not a node the emulator reads")
        for node in [n for n in top if n.tag == "SpecialSequence" and n.get("type") == "BeforeStart"]:
            self.block(_children(node))
        for node in [n for n in top if n.tag in ("SubProgram", "Thread")]:
            self.definition(node)
        for node in [n for n in top if n.tag == "Thread"]:
            thread = _identifier(node.get("name", "Thread"))
            self.emit(f"thread_{thread} = run {thread}()")
        main = next((n for n in top if n.tag == "MainProgram"), None)
        if main is None:
            raise UrpError("no MainProgram node")
        once = main.get("runOnlyOnce", "false") == "true"
        if once:
            self.block(_children(main))
        else:
            self.emit("while (True):")
            self.nested(_children(main))
            self.emit("end")
        if self.external:  # the driver's definitions: the program's header
            self.lines.insert(1, HEADER_MARK)
        self.lines.append("end")  # the one def a controller runs, as in the .script PolyScope saves
        return "\n".join(self.lines) + "\n"

    def definition(self, node: ElementTree.Element) -> None:
        name = _identifier(node.get("name", node.tag))
        if node.tag == "Thread":  # a thread runs its children over and over (once if told so)
            self.emit(f"thread {name}():")
            self.depth += 1
            if node.get("runOnlyOnce", "false") == "true":
                self.block(_children(node))
            else:
                self.emit("while (True):")
                self.nested(_children(node))
                self.emit("end")
            self.depth -= 1
        else:
            self.emit(f"def {name}():")
            self.nested(_children(node))
        self.emit("end")

    def block(self, nodes: list[ElementTree.Element]) -> None:
        pending: list[ElementTree.Element] = []
        for node in nodes:
            if node.tag == "If" and node.get("type") in ("ElseIf", "Else") and pending:
                pending.append(node)
                continue
            if pending:
                self.branches(pending)
                pending = []
            if node.tag == "If":
                pending = [node]
            else:
                self.node(node)
        if pending:
            self.branches(pending)

    def nested(self, nodes: list[ElementTree.Element]) -> None:
        self.depth += 1
        self.block(nodes)
        if not nodes:
            self.emit("sync()")  # an empty body would spin without giving time to the rest
        self.depth -= 1

    def branches(self, nodes: list[ElementTree.Element]) -> None:
        for k, node in enumerate(nodes):
            kind = node.get("type", "If")
            if kind == "Else":
                self.emit("else:")
            else:
                self.emit(f"{'if' if k == 0 else 'elif'} {self.expression(node)}:")
            self.nested(_children(node))
        self.emit("end")

    def node(self, node: ElementTree.Element) -> None:
        tag = node.tag
        if tag == "Comment":
            self.emit(f"# {node.get('comment', '')}".rstrip())
        elif tag == "Folder":
            self.block(_children(node))
        elif tag == "Assignment":
            if node.get("valueSource", "Expression") != "Expression":
                raise UrpError(
                    f"{self.where(node)}: an assignment from {node.get('valueSource')} is not read"
                )
            self.emit(f"global {self.variable(node.find('variable'), node)} = {self.expression(node)}")
        elif tag == "Script":
            self.script(node)
        elif tag == "Loop":
            self.loop(node)
        elif tag == "Move":
            self.move(node)
        elif tag == "Wait":
            self.wait(node)
        elif tag == "Set":
            self.set_output(node)
        elif tag == "Halt":
            self.emit("halt")
        elif tag == "Popup":
            text = (node.get("message") or "").replace('"', "'")
            self.emit(f'popup("{text}", "Message", False, False, blocking=False)')
        elif tag == "Contributed" and node.get("strategyClass") == EXTERNAL_CONTROL:
            self.external = True  # the driver's program goes here when played (external_program.py)
            self.emit(NODE_MARK)
        elif tag == "Call":
            self.emit(f"{_identifier(node.get('subprogram') or node.get('name') or '')}()")
        else:
            raise UrpError(f"{self.where(node)}: <{tag}> is not a node the emulator reads")

    # --- nodes ---------------------------------------------------------------

    def script(self, node: ElementTree.Element) -> None:
        if node.get("type", "Line") == "Line":
            self.emit(self.expression(node))
            return
        text = node.findtext("script") or node.findtext("expression") or ""
        for line in text.splitlines():
            self.emit(line.strip())

    def loop(self, node: ElementTree.Element) -> None:
        kind = node.get("type", "Forever")
        if kind == "Forever":
            self.emit("while (True):")
        elif kind == "While":
            self.emit(f"while ({self.expression(node)}):")
        elif kind in ("Counting", "Counted", "Count"):
            count = node.get("count") or node.get("loops") or node.get("iterations")
            if count is None or not count.isdigit():
                raise UrpError(f"{self.where(node)}: a counted loop without its count")
            self.loops += 1
            counter = f"loop_{self.loops}"
            self.emit(f"global {counter} = 0")
            self.emit(f"while ({counter} < {count}):")
            self.depth += 1
            self.emit(f"global {counter} = {counter} + 1")
            self.depth -= 1
        else:
            raise UrpError(f"{self.where(node)}: a {kind} loop is not read")
        self.nested(_children(node))
        self.emit("end")

    def move(self, node: ElementTree.Element) -> None:
        kind = node.get("motionType", "MoveJ")
        verbs = {"MoveJ": "movej", "MoveL": "movel", "MoveP": "movep"}
        if kind not in verbs:
            raise UrpError(f"{self.where(node)}: a {kind} move is not read")
        speed, accel = node.get("speed"), node.get("acceleration")
        for point in _children(node):
            if point.tag == "Comment":
                continue
            if point.tag != "Waypoint":
                raise UrpError(f"{self.where(point)}: <{point.tag}> inside a move is not read")
            target = self.waypoint(point)
            args = [target]
            args += [f"a={_number(accel, point, self)}"] if accel else []
            args += [f"v={_number(speed, point, self)}"] if speed else []
            params = point.find("motionParameters")
            blend = point.get("blendRadius") or (params.get("blendRadius") if params is not None else None)
            args += [f"r={_number(blend, point, self)}"] if blend else []
            self.emit(f"{verbs[kind]}({', '.join(args)})")

    def waypoint(self, point: ElementTree.Element) -> str:
        kind = point.get("type", "Fixed")
        if kind == "Variable":
            return self.variable(point.find("variable"), point)
        if kind == "Fixed":
            joints = point.find(".//JointAngles")
            angles = joints.get("angles") if joints is not None else None
            if angles:
                return "[" + ", ".join(str(_number(v, point, self)) for v in angles.split(",")) + "]"
            pose = point.find(".//pose")
            if pose is not None and pose.get("pose"):
                return (
                    "p["
                    + ", ".join(str(_number(v, point, self)) for v in pose.get("pose", "").split(","))
                    + "]"
                )
            raise UrpError(f"{self.where(point)}: a fixed waypoint without its joint angles")
        raise UrpError(f"{self.where(point)}: a {kind} waypoint is not read")

    def wait(self, node: ElementTree.Element) -> None:
        kind = node.get("type", "Sleep")
        if kind in ("Sleep", "Time"):
            seconds = node.get("waitTime") or node.get("time") or node.findtext("waitTime")
            self.emit(f"sleep({_number(seconds, node, self)})")
        elif kind == "Expression":
            self.emit(f"while (not ({self.expression(node)})):")
            self.depth += 1
            self.emit("sync()")
            self.depth -= 1
            self.emit("end")
        else:
            raise UrpError(f"{self.where(node)}: a wait for {kind} is not read")

    def set_output(self, node: ElementTree.Element) -> None:
        output = node.find(".//DigitalOutput")
        output = output if output is not None else node.find("pin")
        number = (output.get("pin") or output.get("number")) if output is not None else node.get("pin")
        value = node.get("value") or node.get("digitalValue")
        if number is None or not number.isdigit() or value is None:
            raise UrpError(f"{self.where(node)}: a Set of anything but a standard digital output is not read")
        self.emit(f"set_standard_digital_out({number}, {value.lower() == 'true' or value == '1'})")

    # --- expressions and variables ---------------------------------------------

    def expression(self, node: ElementTree.Element) -> str:
        expr = node.find("expression")
        if expr is None:
            raise UrpError(f"{self.where(node)}: no expression")
        out = []
        for part in expr:
            if part.tag == "ExpressionChar":
                char = part.get("character", "")
                out.append(GLYPHS.get(char, char))
            elif part.tag == "ExpressionToken":
                out.append(part.get("token", ""))
            elif part.tag == "ExpressionVariable":
                out.append(self.variable(next(iter(part), None), part))
            else:
                raise UrpError(f"{self.where(node)}: <{part.tag}> in an expression is not read")
        return "".join(out).strip()

    def variable(self, ref: ElementTree.Element | None, owner: ElementTree.Element) -> str:
        """The name of a variable: its own `name`, or that of the node its `reference` leads to."""
        seen = 0
        while ref is not None and ref.get("name") is None and ref.get("reference") and seen < 16:
            ref = self.follow(ref, ref.get("reference", ""))
            seen += 1
        name = ref.get("name") if ref is not None else None
        if not name or not _NAME.match(name):
            raise UrpError(f"{self.where(owner)}: a variable the emulator cannot name")
        return name

    def follow(self, start: ElementTree.Element, path: str) -> ElementTree.Element:
        """The node an XStream relative reference leads to from `start`."""
        node = start
        for step in path.split("/"):
            if step == "..":
                parent = self.parents.get(node)
                if parent is None:
                    raise UrpError(f"{self.where(start)}: the reference {path!r} leads out of the program")
                node = parent
                continue
            match = _STEP.match(step)
            found = [c for c in node if match is not None and c.tag == match["tag"]]
            index = int(match["index"]) if match is not None and match["index"] else 1
            if len(found) < index:
                raise UrpError(f"{self.where(start)}: the reference {path!r} leads nowhere")
            node = found[index - 1]
        return node

    def where(self, node: ElementTree.Element) -> str:
        steps = []
        while node is not None:
            label = node.get("name") or node.get("type") or node.get("motionType")
            if node.tag != "children":
                steps.append(f"{node.tag}({label})" if label else node.tag)
            node = self.parents.get(node)  # type: ignore[assignment]
        return "/".join(reversed(steps))

    def emit(self, line: str) -> None:
        self.lines.append("  " * self.depth + line)


def _children(node: ElementTree.Element | None) -> list[ElementTree.Element]:
    children = node.find("children") if node is not None else None
    return list(children) if children is not None else []


def _identifier(name: str) -> str:
    ident = re.sub(r"\W", "_", name) or "program"
    return ident if not ident[0].isdigit() else f"p_{ident}"


def _number(text: str | None, node: ElementTree.Element, translator: _Translator) -> float:
    try:
        return float(text or "")
    except ValueError:
        raise UrpError(f"{translator.where(node)}: {text!r} is not a number") from None


__all__ = ["UrpError", "read_urp", "urp_to_script"]
