"""Emit a Wireshark Lua dissector for RTDE (`rtde.<field>`) and the primary interface
(`urprimary.<member>.<field>`: member names keep fields of different sub-packages apart).

Everything comes from the spec: package layouts per type, sender and protocol version;
the data-package fields with their types; enums and bit meanings as value strings.
Data packages are decoded with the recipe seen in the same TCP stream's setup exchange.
"""

from __future__ import annotations

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.schema import LayoutField, Spec

from .render import PY_HEADER

LUA_FIELD = {
    "bool": "uint8", "uint8": "uint8", "int8": "int8", "uint16": "uint16", "int16": "int16",
    "uint32": "uint32", "int32": "int32", "uint64": "uint64", "float": "float", "double": "double",
}  # fmt: skip
INTEGER = {"bool", "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64"}


def lua_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", " ") + '"'


def _field(abbr: str, label: str, prim: str, vs: str | None = None) -> str:
    kind = LUA_FIELD[prim]
    if prim in INTEGER:
        return f"ProtoField.{kind}({lua_str(abbr)}, {lua_str(label)}, base.DEC{', ' + vs if vs else ''})"
    return f"ProtoField.{kind}({lua_str(abbr)}, {lua_str(label)})"


def _value_strings(spec: Spec) -> list[str]:
    out = []
    for enum in spec.all_enums:
        pairs = ", ".join(f"[{v.value}] = {lua_str(v.name)}" for v in enum.values)
        out.append(f"local vs_{enum.name} = {{ {pairs} }}\n")
    return out


def emit_lua(spec: Spec, catalogue: Catalogue) -> str:
    prims = {p.name: p for p in spec.primitives.primitives}
    pk = spec.packages
    lines = [
        PY_HEADER.replace("#", "--", 1),
        "-- Wireshark dissector for Universal Robots RTDE and the primary/secondary interfaces.\n",
        "-- Install: rtde-spec wireshark --install   (or copy to ~/.local/lib/wireshark/plugins/)\n\n",
        'local rtde = Proto("rtde", "Universal Robots RTDE")\n',
        'local urprimary = Proto("urprimary", "Universal Robots primary/secondary interface")\n\n',
    ]
    lines += _value_strings(spec)
    types = ", ".join(f"[{ord(p.code)}] = {lua_str(p.name)}" for p in pk.package_types)
    lines.append(f"local vs_package_type = {{ {types} }}\n\n")
    # --- RTDE fields: the header, every package field, every catalogue field
    lines.append("local F = {}\n")
    lines.append(f"F.size = {_field('rtde.size', 'Size', pk.header[0].type)}\n")
    lines.append(f"F.type = {_field('rtde.type', 'Type', pk.header[1].type, 'vs_package_type')}\n")
    seen: dict[str, str] = {}
    for msg in pk.messages:
        for fld in msg.fields:
            if fld.name in seen:
                continue
            if fld.type in prims:
                vs = f"vs_{fld.enum}" if fld.enum else None
                seen[fld.name] = _field(f"rtde.{fld.name}", fld.name, fld.type, vs)
            elif fld.type == "bytes":
                seen[fld.name] = f'ProtoField.bytes("rtde.{fld.name}", "{fld.name}")'
            else:
                seen[fld.name] = f'ProtoField.string("rtde.{fld.name}", "{fld.name}")'
    wire = catalogue.wire_types
    field_types: dict[str, str] = {}
    for info in catalogue.fields():
        if info.name in seen or info.wire.element is None:
            continue
        vs = f"vs_{info.enum}" if info.enum else None
        seen[info.name] = _field(f"rtde.{info.name}", info.name, info.wire.element, vs)
        field_types[info.name] = info.type
    for name, text in seen.items():
        lines.append(f"F[{lua_str(name)}] = {text}\n")
    lines.append(
        "local fields = {}\nfor _, f in pairs(F) do table.insert(fields, f) end\nrtde.fields = fields\n\n"
    )
    lines.append("-- wire types: element size and count\nlocal WIRE = {\n")
    for w in wire.values():
        if w.element is not None:
            lines.append(
                f"  [{lua_str(w.name)}] = {{ size = {prims[w.element].size}, count = {w.count} }},\n"
            )
    lines.append("}\nlocal FIELD_TYPE = {\n")
    lines += [f"  [{lua_str(n)}] = {lua_str(t)},\n" for n, t in field_types.items()]
    lines.append("}\n\n-- layouts: type/sender/protocol -> fields\nlocal LAYOUT = {\n")
    for msg in pk.messages:
        parts = []
        for fld in msg.fields:
            if fld.type in prims:
                parts.append(
                    f'{{ name = {lua_str(fld.name)}, kind = "prim", size = {prims[fld.type].size} }}'
                )
            elif fld.length == "rest":
                parts.append(f'{{ name = {lua_str(fld.name)}, kind = "rest" }}')
            else:
                size = prims[fld.length or "uint8"].size
                parts.append(f'{{ name = {lua_str(fld.name)}, kind = "prefixed", size = {size} }}')
        for sender in msg.senders:
            for proto in msg.protocols:
                key = f"{ord(msg.type)}/{sender}/{proto}"
                lines.append(f"  [{lua_str(key)}] = {{ name = {lua_str(msg.name)}, {', '.join(parts)} }},\n")
    lines.append("}\n\n")
    senders = [s for s in pk.senders]
    lines.append(
        f'local PORT = {pk.port}\nlocal DIRECTION = {{ {senders[0]} = "{pk.directions[senders[0]]}", '
    )
    lines.append(f'{senders[1]} = "{pk.directions[senders[1]]}" }}\n')
    lines.append(f"local DATA = {ord(next(m.type for m in pk.messages if m.name == 'data_package'))}\n")
    lines.append(f"local RTDE_HEADER = {sum(prims[h.type].size for h in pk.header)}\n")
    lines.append(f"local RTDE_SIZE = {prims[pk.header[0].type].size}  -- the size field leads the header\n")
    data = next(m for m in pk.messages if m.name == "data_package")
    lead = sum(prims[f.type].size for f in data.fields if f.type in prims)
    lines.append(
        f"local PAYLOAD = {sum(prims[h.type].size for h in pk.header) + lead}  -- header, recipe id\n"
    )
    without = ", ".join(
        f'["{sender}/{proto}"] = {rule.implied}'
        for rule in pk.data_recipe_id
        if rule.implied is not None
        for sender in rule.senders
        for proto in rule.protocols
    )
    lines.append("-- sender/protocol -> the recipe of a data package sent without its id (told by size)\n")
    lines.append(f"local WITHOUT_ID = {{ {without} }}\n")
    lines.append(_RTDE_BODY)
    lines += _primary(spec, prims)
    return "".join(lines)


_RTDE_BODY = """
local streams, frames = {}, {}

local function split_names(text)
  local names = {}
  for name in string.gmatch(text .. ",", "([^,]*),") do table.insert(names, name) end
  if #names > 0 and names[#names] == "" then table.remove(names) end
  return names
end

local function payload_size(names)
  local total = 0
  for _, n in ipairs(names) do
    local w = WIRE[FIELD_TYPE[n] or ""]
    if not w then return nil end
    total = total + w.size * w.count
  end
  return total
end

local function stream_state(pinfo)
  local key = tostring(pinfo.src) .. ":" .. pinfo.src_port .. "-" .. tostring(pinfo.dst) .. ":" .. pinfo.dst_port
  if pinfo.dst_port ~= PORT then
    key = tostring(pinfo.dst) .. ":" .. pinfo.dst_port .. "-" .. tostring(pinfo.src) .. ":" .. pinfo.src_port
  end
  local s = streams[key]
  if not s then
    s = { version = 1, pending = {}, recipes = { input = {}, output = {} } }
    streams[key] = s
  end
  return s
end

local function dissect_rtde_pdu(tvb, pinfo, tree)
  local size = tvb(0, RTDE_SIZE):uint()
  local ptype = tvb(RTDE_SIZE, 1):uint()
  local sender = (pinfo.dst_port == PORT) and "client" or "controller"
  local s = stream_state(pinfo)
  local frame = frames[pinfo.number]
  if not frame then
    frame = { version = s.version, recipes = {} }
    frames[pinfo.number] = frame
  end
  local layout = LAYOUT[ptype .. "/" .. sender .. "/" .. frame.version]
  local sub = tree:add(rtde, tvb(0, size), "RTDE " .. (layout and layout.name or "unknown"))
  sub:add(F.size, tvb(0, RTDE_SIZE))
  sub:add(F.type, tvb(RTDE_SIZE, 1))
  pinfo.cols.protocol = "RTDE"
  if not layout then return size end
  local bare = nil  -- the recipe's names when this data package came without its recipe id
  if ptype == DATA then
    if not pinfo.visited then
      local implied = WITHOUT_ID[sender .. "/" .. frame.version]
      local names = implied and s.recipes[DIRECTION[sender]][implied]
      if names and size == RTDE_HEADER + (payload_size(names) or -1) then frame.recipes[size .. "/-"] = names end
    end
    bare = frame.recipes[size .. "/-"]
  end
  local pos, values = RTDE_HEADER, {}
  for _, f in ipairs(layout) do
    if pos > size then break end
    if bare and f.name == "recipe_id" then goto next_field end
    local range
    if f.kind == "prim" then
      if pos + f.size > size then break end
      range = tvb(pos, f.size)
      values[f.name] = range:uint64():tonumber()
      pos = pos + f.size
    elseif f.kind == "prefixed" then
      local n = tvb(pos, f.size):uint()
      range = tvb(pos + f.size, n)
      values[f.name] = range:string()
      pos = pos + f.size + n
    else
      if size > pos then range = tvb(pos, size - pos) end
      values[f.name] = range and range:string() or ""
      pos = size
    end
    if range and f.name ~= "payload" then sub:add(F[f.name], range) end
    ::next_field::
  end
  if not pinfo.visited then
    local name = layout.name
    if name == "request_protocol_version" then s.requested = values.protocol_version
    elseif name == "request_protocol_version_reply" then
      if values.accepted ~= 0 and s.requested then s.version = s.requested end
    elseif name == "setup_outputs_v1" or name == "setup_outputs_v2" then s.pending.output = split_names(values.variable_names)
    elseif name == "setup_inputs" then s.pending.input = split_names(values.variable_names)
    elseif name == "setup_outputs_v1_reply" or name == "setup_outputs_v2_reply" then
      local id = values.output_recipe_id or 1
      if id ~= 0 and s.pending.output then s.recipes.output[id] = s.pending.output end
    elseif name == "setup_inputs_reply" then
      if values.input_recipe_id ~= 0 and s.pending.input then s.recipes.input[values.input_recipe_id] = s.pending.input end
    elseif ptype == DATA and not bare then
      frame.recipes[size .. "/" .. values.recipe_id] = s.recipes[DIRECTION[sender]][values.recipe_id]
    end
  end
  local start = bare and RTDE_HEADER or PAYLOAD
  if ptype == DATA and size > start then
    local names = bare or frame.recipes[size .. "/" .. values.recipe_id]
    if names then
      local p = start
      for _, n in ipairs(names) do
        local w = WIRE[FIELD_TYPE[n] or ""]
        if not w or p + w.size * w.count > size then break end
        for _ = 1, w.count do
          sub:add(F[n], tvb(p, w.size))
          p = p + w.size
        end
      end
    else
      sub:add(F.payload, tvb(start, size - start))
    end
  end
  return size
end

local function rtde_length(tvb, pinfo, offset) return tvb(offset, RTDE_SIZE):uint() end

function rtde.dissector(tvb, pinfo, tree)
  dissect_tcp_pdus(tvb, tree, RTDE_HEADER, rtde_length, dissect_rtde_pdu)
end
DissectorTable.get("tcp.port"):add(PORT, rtde)
"""


def _layout_lua(fields: list[LayoutField], prims: dict, prefix: str, out: dict[str, str]) -> str:  # type: ignore[type-arg]
    """A Lua table walking a member's layout; registers its fields in `out` (abbr -> ProtoField)."""
    parts = []
    for fld in fields:
        abbr = f"{prefix}.{fld.name}"
        kind = fld.kind
        if kind == "value" and fld.type in prims:
            out[abbr] = _field(abbr, fld.name, fld.type or "", f"vs_{fld.enum}" if fld.enum else None)
            parts.append(
                f'{{ kind = "prim", f = {lua_str(abbr)}, size = {prims[fld.type].size}, count = {fld.count or 1} }}'
            )
        elif kind == "repeat" and isinstance(fld.repeat, int):
            inner = _layout_lua(fld.fields or [], prims, abbr, out)
            parts.append(f'{{ kind = "repeat", times = {fld.repeat}, fields = {inner} }}')
        elif kind in ("string", "bytes") and fld.length != "rest" and fld.length in prims:
            out[abbr] = f"ProtoField.string({lua_str(abbr)}, {lua_str(fld.name)})"
            parts.append(f'{{ kind = "prefixed", f = {lua_str(abbr)}, size = {prims[fld.length].size} }}')
        elif kind in ("string", "bytes"):
            out[abbr] = f"ProtoField.string({lua_str(abbr)}, {lua_str(fld.name)})"
            parts.append(f'{{ kind = "rest", f = {lua_str(abbr)} }}')
        else:  # switches, optional groups, typed values: shown as the remaining bytes
            out[abbr] = f"ProtoField.bytes({lua_str(abbr)}, {lua_str(fld.name)})"
            parts.append(f'{{ kind = "rest", f = {lua_str(abbr)} }}')
            break
    return "{ " + ", ".join(parts) + " }"


def _primary(spec: Spec, prims: dict) -> list[str]:  # type: ignore[type-arg]
    pf = spec.primary
    fields: dict[str, str] = {
        "urprimary.size": _field("urprimary.size", "size", pf.header[0].type),
        "urprimary.type": _field("urprimary.type", "type", pf.header[1].type, f"vs_{pf.header[1].enum}" if pf.header[1].enum else None),
        "urprimary.subpackage_type": _field("urprimary.subpackage_type", "sub-package type", pf.subpackage_header[1].type, f"vs_{pf.subpackage_header[1].enum}" if pf.subpackage_header[1].enum else None),
    }  # fmt: skip
    families = []
    for fam in pf.families:
        members = []
        for member in fam.members:
            body = _layout_lua([*fam.prefix, *member.fields], prims, f"urprimary.{member.name}", fields)
            members.append(f"[{member.type}] = {{ name = {lua_str(member.name)}, layout = {body} }}")
        prefix = _layout_lua(fam.prefix, prims, f"urprimary.{fam.name}", fields) if fam.prefix else "{}"
        tag_size = 0
        tag_offset = 0
        for fld in fam.prefix:
            if fld.name == fam.tag:
                tag_size = prims[fld.type or "uint8"].size
                break
            tag_offset += prims[fld.type or "uint8"].size * (fld.count or 1)
        families.append(
            f"[{fam.type}] = {{ name = {lua_str(fam.name)}, layout = {lua_str(fam.layout)}, prefix = {prefix}, "
            f"tag_offset = {tag_offset}, tag_size = {tag_size}, members = {{ {', '.join(members)} }} }}"
        )
    out = ["\nlocal G = {}\n"]
    out += [f"G[{lua_str(abbr)}] = {text}\n" for abbr, text in fields.items()]
    out.append(
        "local gfields = {}\nfor _, f in pairs(G) do table.insert(gfields, f) end\nurprimary.fields = gfields\n"
    )
    out.append("local FAMILIES = {\n" + "".join(f"  {f},\n" for f in families) + "}\n")
    ports = ", ".join(str(p) for p in pf.ports.values())
    sub_header = sum(prims[h.type].size for h in pf.subpackage_header)
    header = sum(prims[h.type].size for h in pf.header)
    out.append(
        f"local PRIMARY_PORTS = {{ {ports} }}\nlocal SUB_HEADER = {sub_header}\nlocal HEADER = {header}\n"
    )
    out.append(
        f"local P_SIZE = {prims[pf.header[0].type].size}\nlocal SUB_SIZE = {prims[pf.subpackage_header[0].type].size}\n"
    )
    out.append(_PRIMARY_BODY)
    return out


_PRIMARY_BODY = """
local function walk(tvb, tree, layout, pos, stop)
  for _, f in ipairs(layout) do
    if pos >= stop then return pos end
    if f.kind == "prim" then
      for _ = 1, f.count do
        if pos + f.size > stop then return stop end
        tree:add(G[f.f], tvb(pos, f.size))
        pos = pos + f.size
      end
    elseif f.kind == "repeat" then
      for _ = 1, f.times do pos = walk(tvb, tree, f.fields, pos, stop) end
    elseif f.kind == "prefixed" then
      if pos + f.size > stop then return stop end
      local n = tvb(pos, f.size):uint()
      if pos + f.size + n > stop then n = stop - pos - f.size end
      tree:add(G[f.f], tvb(pos + f.size, n))
      pos = pos + f.size + n
    else
      tree:add(G[f.f], tvb(pos, stop - pos))
      pos = stop
    end
  end
  return pos
end

local function dissect_primary_pdu(tvb, pinfo, tree)
  local size = tvb(0, P_SIZE):uint()
  local mtype = tvb(P_SIZE, 1):uint()
  local fam = FAMILIES[mtype]
  local sub = tree:add(urprimary, tvb(0, size), "UR primary " .. (fam and fam.name or "message"))
  sub:add(G["urprimary.size"], tvb(0, P_SIZE))
  sub:add(G["urprimary.type"], tvb(P_SIZE, 1))
  pinfo.cols.protocol = "URPRIMARY"
  if not fam then return size end
  if fam.layout == "subpackages" then
    local pos = HEADER
    while pos + SUB_HEADER <= size do
      local n = tvb(pos, SUB_SIZE):uint()
      if n < SUB_HEADER or pos + n > size then break end
      local stype = tvb(pos + SUB_SIZE, 1):uint()
      local member = fam.members[stype]
      local st = sub:add(urprimary, tvb(pos, n), member and member.name or ("sub-package " .. stype))
      st:add(G["urprimary.subpackage_type"], tvb(pos + SUB_SIZE, 1))
      if member then walk(tvb, st, member.layout, pos + SUB_HEADER, pos + n) end
      pos = pos + n
    end
  elseif fam.layout == "tagged" and fam.tag_size > 0 and size >= HEADER + fam.tag_offset + fam.tag_size then
    local tag = tvb(HEADER + fam.tag_offset, fam.tag_size):uint()
    local member = fam.members[tag]
    if member then walk(tvb, sub, member.layout, HEADER, size) else walk(tvb, sub, fam.prefix, HEADER, size) end
  end
  return size
end

local function primary_length(tvb, pinfo, offset) return tvb(offset, P_SIZE):uint() end

local FROM_CONTROLLER = {}
for _, port in ipairs(PRIMARY_PORTS) do FROM_CONTROLLER[port] = true end

function urprimary.dissector(tvb, pinfo, tree)
  if FROM_CONTROLLER[pinfo.src_port] then  -- what clients send is URScript text
    dissect_tcp_pdus(tvb, tree, HEADER, primary_length, dissect_primary_pdu)
  end
end
for _, port in ipairs(PRIMARY_PORTS) do DissectorTable.get("tcp.port"):add(port, urprimary) end
"""
