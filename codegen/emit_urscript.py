"""Emit _generated/urscript_functions.py and docs/reference/urscript.md from spec/urscript/.

URScript's built-ins are a table of functions, not a wire layout, so they have their own
meta-model (rtde_spec.metamodel.urscript) and their own emitter.
"""

from __future__ import annotations

import json

from rtde_spec.metamodel.urscript import ScriptFunctions

from .render import GEN, MD_HEADER, PY_HEADER, literal_module, md_table


def emit_urscript(table: ScriptFunctions) -> dict[str, str]:
    """Relative output path -> text, for the URScript built-ins of the loaded spec bundle."""
    return {
        f"{GEN}/urscript_functions.py": _python(table),
        f"{GEN}/urscript_ports.py": _ports(table),
        "docs/reference/urscript.md": _markdown(table),
    }


def _ports(table: ScriptFunctions) -> str:
    """The interpreter socket's port on its own: the CLI names it without loading the table."""
    kind = "int" if table.interpreter_port else "int | None"
    return (
        PY_HEADER
        + '"""The port URScript itself serves (spec/urscript/functions.yaml)."""\n\n'
        + f"INTERPRETER_PORT: {kind} = {table.interpreter_port!r}\n"
        + '"""The interpreter socket of a program in interpreter_mode() (None: the spec names none)."""\n'
    )


def _python(table: ScriptFunctions) -> str:
    return literal_module(
        "URScript built-in functions of spec/urscript/functions.yaml.",
        "URSCRIPT_FUNCTIONS",
        table.model_dump(mode="json", exclude_unset=True),
    )


def _signature(table: ScriptFunctions, name: str) -> str:
    function = next(f for f in table.functions if f.name == name)
    parts = [p.name if p.required else f"{p.name}={json.dumps(p.default)}" for p in function.params]
    return f"`{name}({', '.join(parts)})`"


def _markdown(table: ScriptFunctions) -> str:
    out = [
        MD_HEADER,
        "# URScript built-in functions\n\n",
        "The functions a program sent to the emulator may call without defining them, each as the\n",
        f"Script Manual lists it ({table.doc_ref}). `since` is the first version per product line\n",
        "(a line not named does not have it, except PolyScope X, which has the e-Series ones from\n",
        "10.0); *unchecked* marks a `since` taken as the line's first\n",
        "release where the editions on hand do not say. The emulator implements every one; where it\n",
        "cannot do what a robot does physically it approximates, as the last column says.\n\n",
        "The emulator's URScript: lexer, parser (grammar in `rtde_spec/emulator/urscript/grammar.ebnf`),\n",
        "checker and interpreter, with threads scheduled on the control step.\n",
    ]
    for section in ("motion", "internals", "interfaces", "worldmodel", "maths"):
        rows = []
        for f in table.functions:
            if f.section != section:
                continue
            since = ", ".join(f"{line} {v}" for line, v in f.since.items()) + (
                "" if f.checked else " *unchecked*"
            )
            rows.append((_signature(table, f.name), f.returns, since, f.doc, f.emulation or ""))
        out.append(f"\n## Module {section}\n\n")
        out.append(md_table(["function", "returns", "since", "what it does", "in the emulator"], rows))
    return "".join(out)
