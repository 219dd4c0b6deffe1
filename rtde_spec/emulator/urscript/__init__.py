"""URScript as the controller reads it: lexer → parser → checker → interpreter, in that order.

`parse` gives the syntax tree (`nodes`), `check` refuses unknown names before anything runs (as
the controller compiles first), and `interpreter.Program` runs the main program and its threads
on the control step. The grammar is `grammar.ebnf` beside this file.
"""

from rtde_spec.emulator.urscript.nodes import Branch, Expr, Function, Script, ScriptFault, Stmt
from rtde_spec.emulator.urscript.parser import parse, parse_program

__all__ = ["Branch", "Expr", "Function", "Script", "ScriptFault", "Stmt", "parse", "parse_program"]
