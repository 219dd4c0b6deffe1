"""The names of a program's global variables, as a controller lists them when the program starts.

The primary interface's Global Variables Setup message carries "the list of global variables",
"sent once when program starts" (UR's primary/secondary interface document); update messages
then give their values in that order every 100 ms. A controller knows them from the compiled
program: the variables the program assigns at its own level (the program def's body, or a
script's top-level statements, `if`/`while` bodies included) and those its functions declare
`global`, each once, in the order the program first writes them.
"""

from __future__ import annotations

from rtde_spec.emulator.urscript.nodes import Script, Stmt


def global_names(script: Script) -> tuple[str, ...]:
    """The program's global variable names, first assignment first."""
    own = (
        script.functions[script.name].body
        if script.wrapped and script.name in script.functions
        else script.main
    )
    names: dict[str, None] = {}
    _collect(own, names, program_level=True)
    for function in script.functions.values():
        if function.body is not own:
            _collect(function.body, names, program_level=False)
    return tuple(names)


def _collect(body: list[Stmt], names: dict[str, None], program_level: bool) -> None:
    for stmt in body:
        if stmt.kind == "assign" and not stmt.index and (program_level or stmt.scope == "global"):
            names.setdefault(stmt.name, None)
        for branch in stmt.branches:
            _collect(branch.body, names, program_level)
