"""Emit the Wireshark Lua dissectors of a driver session's other ports, appended to rtde_spec.lua:
URCL's external control ports (emit_lua_external.py), the dashboard (`urdashboard.*`: command
and reply outcome from the spec's reply texts) and the real-time interface (`urrealtime.*`,
the layout by size).
"""

from __future__ import annotations

import string

from rtde_spec.metamodel.bundle import SpecBundle
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.dashboard import DashboardFile
from rtde_spec.metamodel.realtime import PRIMITIVES as RT_PRIMITIVES
from rtde_spec.metamodel.realtime import RealtimeFile, layouts

from .emit_lua import LUA_FIELD, lua_str
from .emit_lua_external import emit_lua_external


def emit_lua_drivers(bundle: SpecBundle) -> str:
    out = ["\n-- ===== UR client library (URCL) external control, dashboard, real-time =====\n"]
    out.append(emit_lua_external(bundle.external, bundle.primitives))
    out.append(_dashboard(bundle.dashboard))
    out.append(_realtime(bundle.realtime, bundle.catalogue))
    return "".join(out)


def _lua_pattern(text: str) -> str:
    """A reply text as an anchored Lua pattern: literal parts escaped, {placeholders} any text."""
    out = []
    for literal, name, _, _ in string.Formatter().parse(text):
        out.append("".join("%" + c if c in "^$()%.[]*+-?" else c for c in literal))
        if name is not None:
            out.append(".*")
    return "^" + "".join(out) + "$"


def _dashboard(table: DashboardFile) -> str:
    rows = []
    for c in sorted(table.commands, key=lambda c: -len(c.command)):
        replies = ", ".join(f"{{ {lua_str(k)}, {lua_str(_lua_pattern(v))} }}" for k, v in c.replies.items())
        rows.append(
            f"  {{ text = {lua_str(c.command)}, arg = {str(c.argument is not None).lower()},"
            f" replies = {{ {replies} }} }},\n"
        )
    return (
        f"\nlocal DASH_PORT = {table.port}\nlocal DASH_UNKNOWN = {lua_str(_lua_pattern(table.unknown))}\n"
        + "local DASH_COMMANDS = {\n"
        + "".join(rows)
        + "}\n"
        + _DASHBOARD_BODY
    )


_DASHBOARD_BODY = """local urdash = Proto("urdashboard", "UR dashboard server")
local FD = {
  request = ProtoField.string("urdashboard.request", "request"),
  reply = ProtoField.string("urdashboard.reply", "reply"),
  command = ProtoField.string("urdashboard.command", "command"),
  argument = ProtoField.string("urdashboard.argument", "argument"),
  outcome = ProtoField.string("urdashboard.outcome", "outcome"),
}
urdash.fields = { FD.request, FD.reply, FD.command, FD.argument, FD.outcome }
local dash_streams, dash_frames = {}, {}

local function dash_command(line)
  for _, c in ipairs(DASH_COMMANDS) do
    if line == c.text then return c, "" end
    if c.arg and line:sub(1, #c.text + 1) == c.text .. " " then return c, line:sub(#c.text + 2) end
  end
  return nil, ""
end

local function dash_outcome(c, reply)
  if c then for _, r in ipairs(c.replies) do if reply:match(r[2]) then return r[1] end end end
  if reply:match(DASH_UNKNOWN) then return "unknown" end
  return "unexpected"
end

function urdash.dissector(tvb, pinfo, tree)
  local text = tvb():string()
  local last = text:match(".*()\\n")
  if not last then pinfo.desegment_len = DESEGMENT_ONE_MORE_SEGMENT; return end
  if last < #text then pinfo.desegment_offset = last; pinfo.desegment_len = DESEGMENT_ONE_MORE_SEGMENT end
  pinfo.cols.protocol = "URDASHBOARD"
  local key = (pinfo.src_port == DASH_PORT) and (tostring(pinfo.dst) .. ":" .. pinfo.dst_port)
    or (tostring(pinfo.src) .. ":" .. pinfo.src_port)
  local s = dash_streams[key]
  if not s then s = { open = {}, greeted = false }; dash_streams[key] = s end
  local results = dash_frames[pinfo.number]
  if not results then
    results = {}
    for line in text:sub(1, last):gmatch("([^\\n]*)\\n") do
      line = line:gsub("\\r$", "")
      if pinfo.src_port == DASH_PORT then
        local c = table.remove(s.open, 1)
        local r = { reply = line, command = "", outcome = s.greeted and "unrequested" or "greeting" }
        if c then r.command = c.c and c.c.text or ""; r.outcome = dash_outcome(c.c, line) end
        table.insert(results, r)
        s.greeted = true
      else
        local c, arg = dash_command(line)
        table.insert(s.open, { c = c })
        table.insert(results, { request = line, command = c and c.text or "", argument = arg })
      end
    end
    dash_frames[pinfo.number] = results
  end
  for _, r in ipairs(results) do
    local sub = tree:add(urdash, tvb(0, last), "UR dashboard " .. (r.request and "request" or "reply"))
    if r.request then
      sub:add(FD.request, tvb(0, last), r.request)
      sub:add(FD.argument, tvb(0, last), r.argument)
    else
      sub:add(FD.reply, tvb(0, last), r.reply)
      sub:add(FD.outcome, tvb(0, last), r.outcome)
    end
    sub:add(FD.command, tvb(0, last), r.command)
  end
end
DissectorTable.get("tcp.port"):add(DASH_PORT, urdash)
"""


def _realtime(table: RealtimeFile, catalogue: Catalogue) -> str:
    by_size: dict[int, str] = {}
    fields: dict[str, str] = {}
    for plan in layouts(table, catalogue):
        parts = []
        for f in plan.fields:
            abbr = f"urrealtime.{f.name}"
            fields.setdefault(abbr, f"ProtoField.{LUA_FIELD[f.type]}({lua_str(abbr)}, {lua_str(f.name)})")
            size = RT_PRIMITIVES[f.type][1]
            parts.append(f"{{ f = {lua_str(abbr)}, size = {size}, count = {f.count or 1} }}")
        by_size.setdefault(plan.size, "{ " + ", ".join(parts) + " }")
    ports = ", ".join(str(p) for p in table.ports.values())
    return (
        '\nlocal urrt = Proto("urrealtime", "UR real-time interface")\nlocal FRT = {}\n'
        + "".join(f"FRT[{lua_str(k)}] = {v}\n" for k, v in fields.items())
        + "local rt_list = {}\nfor _, f in pairs(FRT) do table.insert(rt_list, f) end\n"
        + "local RT_LAYOUTS = {\n"
        + "".join(f"  [{size}] = {body},\n" for size, body in sorted(by_size.items()))
        + f"}}\nlocal RT_PORTS = {{ {ports} }}\n"
        + _REALTIME_BODY
    )


_REALTIME_BODY = """local RT_SIZE = ProtoField.int32("urrealtime.message_size", "message_size")
table.insert(rt_list, RT_SIZE)
urrt.fields = rt_list
local function rt_one(tvb, pinfo, tree)
  local size = tvb(0, 4):int()
  pinfo.cols.protocol = "URREALTIME"
  local sub = tree:add(urrt, tvb(0, size), "UR real-time message")
  sub:add(RT_SIZE, tvb(0, 4))
  local layout = RT_LAYOUTS[size]
  if not layout then return size end
  local pos = 4
  for _, f in ipairs(layout) do
    for _ = 1, f.count do
      if pos + f.size > size then return size end
      sub:add(FRT[f.f], tvb(pos, f.size))
      pos = pos + f.size
    end
  end
  return size
end
local function rt_len(tvb, pinfo, offset) return tvb(offset, 4):int() end
local RT_FROM = {}
for _, port in ipairs(RT_PORTS) do RT_FROM[port] = true end
function urrt.dissector(tvb, pinfo, tree)
  if RT_FROM[pinfo.src_port] then dissect_tcp_pdus(tvb, tree, 4, rt_len, rt_one) end
end
for _, port in ipairs(RT_PORTS) do DissectorTable.get("tcp.port"):add(port, urrt) end
"""
