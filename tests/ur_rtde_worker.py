"""The process ur_rtde's clients live in for a test (tests/ur_rtde_robot.py `Clients` drives it).

ur_rtde holds the GIL while it waits for a reply, so a test calling it in its own process could not
even notice a hang; here the test's process waits for each answer with a deadline instead. One JSON
request a line on stdin: `{"name", "new": [module, class], "args"}` makes a client, `{"name",
"method", "args"}` calls one; each answer is one stdout line after `REPLY` (ur_rtde writes its own
warnings to stdout too): `{"ok": value}` or `{"error": exception class, "message": text}`.
"""

from __future__ import annotations

import importlib
import json
import sys
from typing import Any

REPLY = "@ur_rtde_worker "


def answer(objects: dict[str, Any], request: dict[str, Any]) -> dict[str, Any]:
    try:
        if "new" in request:
            module, cls = request["new"]
            objects[request["name"]] = getattr(importlib.import_module(module), cls)(*request["args"])
            return {"ok": None}
        return {"ok": getattr(objects[request["name"]], request["method"])(*request["args"])}
    except Exception as exc:  # the test decides what a client's exception means
        return {"error": type(exc).__name__, "message": str(exc)}


def main() -> None:
    objects: dict[str, Any] = {}
    for line in sys.stdin:
        reply = answer(objects, json.loads(line))
        sys.stdout.write(REPLY + json.dumps(reply, default=repr) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
