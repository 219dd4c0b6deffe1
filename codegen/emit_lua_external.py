"""Emit the Wireshark Lua dissectors of URCL's external control ports, appended to rtde_spec.lua:
the reverse, trajectory and script command records (`urcl_reverse.*`, `urcl_trajectory.*`,
`urcl_script_command.*`: scaled words shown in SI units) and the script sender
(`urcl_script_sender.*`).

A message with `older` layouts (the reverse command, the trajectory point, the script command)
is decoded with the layout its session uses: the protocol's preference names one, or in `auto`
the program the driver sent the same robot on the script sender port earlier in the capture
does, by the spec's `detect` lines and the rule capture uses (rtde_spec/external/layouts.py),
else the newest. Each record shows the layout and why as generated fields (`<proto>.layout`,
`<proto>.layout_reason`); an older layout's fields are named `<proto>.<layout>.<field>`, with
that layout's scales.
"""

from __future__ import annotations

from rtde_spec.metamodel.external import (
    ExternalControlFile,
    ExternalProtocol,
    OlderRecord,
    RecordMessage,
    Variant,
)
from rtde_spec.metamodel.schema import Primitive

from .emit_lua import LUA_FIELD, lua_str

# the fields a record shows besides its words (layout and its reason: a message with older layouts)
SHOWN = ("variant", "layout", "layout_reason")


def emit_lua_external(external: ExternalControlFile, prims: dict[str, Primitive]) -> str:
    out = []
    for enum in external.enums:
        pairs = ", ".join(f"[{v.value}] = {lua_str(v.name)}" for v in enum.values)
        out.append(f"local vs_urcl_{enum.name} = {{ {pairs} }}\n")
    script = next((p for p in external.protocols if p.request is not None), None)
    out.append(f"local URCL_SCRIPT_PORT = {script.port if script is not None else 'nil'}\n")
    out.append(_RECORDS_BODY)
    for proto in external.protocols:
        out.append(_script_sender(proto) if proto.request is not None else _records(proto, prims))
    return "".join(out)


def _records(proto: ExternalProtocol, prims: dict[str, Primitive]) -> str:
    name = f"urcl_{proto.name}"
    fields: dict[str, str] = {"variant": f'ProtoField.string("{name}.variant", "variant")'}
    if sum(1 for m in proto.messages if m.older) > 1:
        raise ValueError(f"{name}: one message with older layouts per protocol (one preference names them)")
    sides = []
    for msg in proto.messages:
        if not msg.older:
            sides.append(f"  {msg.sender} = {_layout(name, '', msg, prims, fields)},\n")
            continue
        fields["layout"] = f'ProtoField.string("{name}.layout", "layout")'
        fields["layout_reason"] = f'ProtoField.string("{name}.layout_reason", "layout reason")'
        records: list[RecordMessage | OlderRecord] = [msg, *msg.older]
        names = [layout for _, layout, _, _ in msg.layouts()]
        bodies = [
            _layout(name, "" if i == 0 else f"{layout}.", rec, prims, fields, layout)
            for i, (layout, rec) in enumerate(zip(names, records, strict=True))
        ]
        pref = lua_str(f"{msg.name.replace('_', ' ').capitalize()} layout")
        joined = ",\n    ".join(bodies)
        sides.append(f"  {msg.sender} = {{ pref = {pref}, layouts = {{\n    {joined} }} }},\n")
    lines = [f'\nlocal p_{name} = Proto("{name}", {lua_str("URCL " + proto.name.replace("_", " "))})\n']
    lines.append(f"local F_{name} = {{}}\n")
    lines += [f"F_{name}[{lua_str(k)}] = {v}\n" for k, v in fields.items()]
    lines.append(f"local REC_{name} = {{\n{''.join(sides)}}}\n")
    lines.append(f"urcl_records(p_{name}, F_{name}, REC_{name}, {proto.port}, {lua_str(name.upper())})\n")
    return "".join(lines)


def _layout(
    proto: str,
    prefix: str,
    rec: RecordMessage | OlderRecord,
    prims: dict[str, Primitive],
    fields: dict[str, str],
    layout: str | None = None,
) -> str:
    """A record layout's Lua table; `prefix` ("" or "<layout>.") names its fields apart from the newest's."""
    sel_at, variants, default = None, [], "nil"
    for v in rec.variants:
        body, at = _variant(proto, prefix, v, prims, fields, rec.selector)
        sel_at = at if at is not None else sel_at
        if v.when is None:
            default = body
        variants += [f"[{value}] = {body}" for value in v.when or []]
    head = f"name = {lua_str(layout)}, " if layout is not None else ""
    if rec.detect is not None:
        lines = ", ".join(lua_str(line) for line in sorted(rec.detect.lines))
        head += f"detect = {{ {lines} }}, "
        if rec.detect.absent:
            without = ", ".join(lua_str(line) for line in sorted(rec.detect.absent))
            head += f"without = {{ {without} }}, "
        if rec.detect.any_multipliers:
            names = ", ".join(f"[{lua_str(name)}] = true" for name in sorted(rec.detect.any_multipliers))
            head += f"any_mult = {{ {names} }}, "
    sel = "nil" if sel_at is None else str(sel_at)
    return (
        f"{{ {head}size = {rec.record_bytes}, sel_at = {sel}, default = {default},\n"
        f"    variants = {{ {', '.join(variants)} }} }}"
    )


def _variant(
    proto: str,
    prefix: str,
    v: Variant,
    prims: dict[str, Primitive],
    fields: dict[str, str],
    selector: str | None,
) -> tuple[str, int | None]:
    parts, pos, sel_at = [], 0, None
    for f in v.fields:
        prim = prims[f.type]
        key = prefix + f.name
        abbr = f"{proto}.{key}"
        if key in SHOWN:
            raise ValueError(f"{abbr}: the name of a field every record shows")
        if f.scale is not None:
            text = f"ProtoField.double({lua_str(abbr)}, {lua_str(f.name)})"
        else:
            vs = f", base.DEC, vs_urcl_{f.enum}" if f.enum else ", base.DEC"
            text = f"ProtoField.{LUA_FIELD[f.type]}({lua_str(abbr)}, {lua_str(f.name)}{vs})"
        if fields.setdefault(key, text) != text:
            raise ValueError(f"{abbr}: one name, two field kinds in the variants")
        scale = repr(f.scale) if f.scale is not None else "nil"
        parts.append(f"{{ f = {lua_str(key)}, size = {prim.size}, count = {f.count or 1}, scale = {scale} }}")
        if f.name == selector:
            sel_at = pos
        pos += prim.size * (f.count or 1)
    return f"{{ name = {lua_str(v.name)}, fields = {{ {', '.join(parts)} }} }}", sel_at


_RECORDS_BODY = """
-- The program text the driver sent each robot on the script sender port, first pass, in
-- capture order: robot address -> { port = the robot's port, chunks = {}, frames = {}, version = n }.
local urcl_programs = {}

local function urcl_program_add(robot, port, number, text)
  local p = urcl_programs[robot]
  if not p or p.port ~= port then
    p = { port = port, chunks = {}, frames = {}, version = 0 }
    urcl_programs[robot] = p
  end
  if p.frames[number] then return end
  p.frames[number] = true
  table.insert(p.chunks, text)
  p.version = p.version + 1
end

-- The layouts whose detect lines a program has and whose `without` lines it has not, unless it
-- sets a multiplier (MULT_...) they do not name and whose value matters to them (not in
-- any_mult): lines compared without whitespace and `#` comments; a last line without its
-- newline is not read yet (it may be cut short).
local function urcl_named(layouts, text)
  local lines, mult = {}, {}
  local last = text:find("\\n[^\\n]*$")
  for line in text:sub(1, last or 0):gmatch("([^\\n]*)\\n") do
    line = line:gsub("#.*", ""):gsub("%s", "")
    lines[line] = true
    local name = line:match("^(MULT_[%w_]*)=")
    if name then mult[line] = name end
  end
  local named = {}
  for _, l in ipairs(layouts) do
    local ok = l.detect ~= nil
    for _, line in ipairs(l.detect or {}) do ok = ok and lines[line] == true end
    for _, line in ipairs(l.without or {}) do ok = ok and lines[line] ~= true end
    for line, name in pairs(mult) do
      ok = ok and (l.detect_set[line] == true or (l.any_mult or {})[name] == true)
    end
    if ok then table.insert(named, l.name) end
  end
  return named
end

-- fixed records of int32 words; the side the port belongs to (the driver) sends REC.driver.
-- A side with `layouts` (newest first) is read with the one the preference names or, in
-- auto, the one the robot's program names (chosen per robot address), else the newest.
local function urcl_records(proto, F, REC, port, label)
  local list = {}
  for _, f in pairs(F) do table.insert(list, f) end
  proto.fields = list
  local chosen, frame_layout = {}, {}  -- robot address -> program choice; frame -> { layout, why }
  for _, r in pairs(REC) do
    if r.layouts then
      local choices = { { 1, "auto", 0 } }
      for i, l in ipairs(r.layouts) do
        table.insert(choices, { i + 1, l.name, i })
        l.detect_set = {}
        for _, line in ipairs(l.detect or {}) do l.detect_set[line] = true end
      end
      proto.prefs.layout = Pref.enum(r.pref, 0,
        "auto: the layout the program sent on the script sender port names, else the newest", choices, false)
    end
  end
  function proto.init()
    chosen, frame_layout = {}, {}
  end
  local function side(pinfo) return (pinfo.src_port == port) and "driver" or "robot" end
  local function from_program(r, robot)
    local p = urcl_programs[robot]
    if not p then return { r.layouts[1], "no program seen: newest" } end
    local c = chosen[robot]
    if c and c.program == p and c.version == p.version then return c.choice end
    local named = urcl_named(r.layouts, table.concat(p.chunks))
    local choice = { r.layouts[1], "the program on " .. URCL_SCRIPT_PORT .. " names none: newest" }
    if #named == 1 then
      for _, l in ipairs(r.layouts) do
        if l.name == named[1] then choice = { l, "from the program on " .. URCL_SCRIPT_PORT } end
      end
    elseif #named > 1 then
      local which = table.concat(named, ", ")
      choice[2] = "the program on " .. URCL_SCRIPT_PORT .. " names several (" .. which .. "): newest"
    end
    chosen[robot] = { program = p, version = p.version, choice = choice }
    return choice
  end
  -- the layout of this frame's records and why; the first pass decides for later visits
  local function layout_of(r, pinfo)
    if not r.layouts then return r, nil end
    if proto.prefs.layout ~= 0 then return r.layouts[proto.prefs.layout], "preference" end
    local c = frame_layout[pinfo.number]
    if not c then
      c = from_program(r, tostring(pinfo.dst))
      frame_layout[pinfo.number] = c
    end
    return c[1], c[2]
  end
  local function get_len(tvb, pinfo, offset)
    local r = REC[side(pinfo)]
    if not r then return tvb:len() - offset end
    return (layout_of(r, pinfo)).size
  end
  local function one(tvb, pinfo, tree)
    local r = REC[side(pinfo)]
    pinfo.cols.protocol = label
    if not r then
      tree:add(proto, tvb(), label .. " bytes this side does not send")
      return tvb:len()
    end
    local l, why = layout_of(r, pinfo)
    local v = l.default
    if l.sel_at then v = l.variants[tvb(l.sel_at, 4):int()] or l.default end
    local title = label .. " " .. (v and v.name or "record") .. (why and (" (" .. l.name .. ")") or "")
    local sub = tree:add(proto, tvb(0, l.size), title)
    if why then
      sub:add(F["layout"], tvb(0, l.size), l.name):set_generated()
      sub:add(F["layout_reason"], tvb(0, l.size), why):set_generated()
    end
    if not v then return l.size end
    sub:add(F["variant"], tvb(0, l.size), v.name)
    local pos = 0
    for _, f in ipairs(v.fields) do
      for _ = 1, f.count do
        local range = tvb(pos, f.size)
        if f.scale then sub:add(F[f.f], range, range:int() / f.scale) else sub:add(F[f.f], range) end
        pos = pos + f.size
      end
    end
    return l.size
  end
  function proto.dissector(tvb, pinfo, tree) dissect_tcp_pdus(tvb, tree, 4, get_len, one) end
  DissectorTable.get("tcp.port"):add(port, proto)
end
"""


def _script_sender(proto: ExternalProtocol) -> str:
    name = f"urcl_{proto.name}"
    return f"""
local p_{name} = Proto("{name}", "URCL script sender")
local F_{name} = {{
  request = ProtoField.string("{name}.request", "request"),
  script = ProtoField.string("{name}.script", "script text"),
}}
p_{name}.fields = {{ F_{name}.request, F_{name}.script }}
function p_{name}.init() urcl_programs = {{}} end
function p_{name}.dissector(tvb, pinfo, tree)
  pinfo.cols.protocol = "URCL_SCRIPT"
  local sub = tree:add(p_{name}, tvb(), "URCL script sender")
  if pinfo.src_port == {proto.port} then
    sub:add(F_{name}.script, tvb())
    if not pinfo.visited then
      urcl_program_add(tostring(pinfo.dst), pinfo.dst_port, pinfo.number, tvb:raw())
    end
  else sub:add(F_{name}.request, tvb(), (tvb():string():gsub("\\n$", ""))) end
end
DissectorTable.get("tcp.port"):add({proto.port}, p_{name})
"""
