"""Read spec/ YAML into the meta-model, turning every problem into a SpecIssue.

Problems name the file, the path inside it (with the entry's name where it has
one), the line, and the reason. All problems are collected before raising.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from rtde_spec.errors import SpecError, SpecIssue
from rtde_spec.metamodel import safe_yaml
from rtde_spec.metamodel.lint import lint_fields_file, lint_spec
from rtde_spec.metamodel.lint_facts import lint_recipe_id_rules
from rtde_spec.metamodel.schema import (
    EnumsFile,
    FieldsFile,
    PackagesFile,
    PrimaryFile,
    PrimitivesFile,
    ProductLinesFile,
    Spec,
    TypesFile,
)

#: part of the Spec -> (file below the spec root, model of that file)
SPEC_FILES: dict[str, tuple[str, type[BaseModel]]] = {
    "primitives": ("common/primitives.yaml", PrimitivesFile),
    "product_lines": ("common/product_lines.yaml", ProductLinesFile),
    "types": ("rtde/types.yaml", TypesFile),
    "fields": ("rtde/fields.yaml", FieldsFile),
    "enums": ("rtde/enums.yaml", EnumsFile),
    "packages": ("rtde/packages.yaml", PackagesFile),
    "primary_enums": ("primary/enums.yaml", EnumsFile),
    "primary": ("primary/interface.yaml", PrimaryFile),
}

Loc = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)

#: libyaml's loader where PyYAML has it: the spec parses in a tenth of the time (codegen, spec import)
_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def default_spec_root() -> Path:
    """spec/ of a source checkout (the package itself ships generated data instead)."""
    return Path(__file__).resolve().parent.parent / "spec"


def format_path(loc: Loc, data: Any = None) -> str:
    """outputs[3](safety_status).since.cb3 — the entry name helps find it by eye."""
    out = ""
    node = data
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
            node = node[part] if isinstance(node, list) and part < len(node) else None
            if isinstance(node, dict) and isinstance(node.get("name"), str):
                out += f"({node['name']})"
        else:
            out += f".{part}" if out else str(part)
            node = node.get(part) if isinstance(node, dict) else None
    return out


def line_of(node: yaml.Node | None, loc: Loc) -> int | None:
    """1-based line of the deepest YAML node that `loc` reaches."""
    line = node.start_mark.line + 1 if node is not None else None
    for part in loc:
        if isinstance(node, yaml.MappingNode):
            match = [v for k, v in node.value if k.value == part]
            if not match:
                # an unknown key: point at the key itself
                keys = [k for k, _ in node.value if k.value == part]
                return keys[0].start_mark.line + 1 if keys else line
            node = match[0]
        elif isinstance(node, yaml.SequenceNode) and isinstance(part, int):
            if part >= len(node.value):
                return line
            node = node.value[part]
        else:
            return line
        line = node.start_mark.line + 1
    return line


class _Source:
    """One parsed YAML file: its data and node tree, for locating issues."""

    def __init__(self, path: Path, label: str):
        self.label = label
        text = path.read_text(encoding="utf-8")
        safe_yaml.check(text)  # extra-field files come from users: no aliases, bounded depth
        self.node = yaml.compose(text, Loader=_LOADER)
        self.data = yaml.load(text, Loader=_LOADER)  # a safe loader, C or Python

    def issue(self, loc: Loc, reason: str) -> SpecIssue:
        return SpecIssue(self.label, format_path(loc, self.data), reason, line_of(self.node, loc))


def _reason(err: Any) -> str:
    key = err["loc"][-1] if err["loc"] else ""
    if err["type"] == "extra_forbidden":
        return f"unknown key {key!r}"
    if err["type"] == "missing":
        return f"missing required key {key!r}"
    msg = str(err["msg"]).removeprefix("Value error, ")
    return msg


def _validate(source: _Source, model: type[BaseModel], issues: list[SpecIssue]) -> Any:
    data = source.data if source.data is not None else {}
    if not isinstance(data, dict):  # else "Input should be a valid dictionary or instance of FieldsFile"
        kind = "a list" if isinstance(data, list) else f"{type(data).__name__} {data!r:.40}"
        issues.append(
            source.issue((), f"the file is a mapping ({', '.join(model.model_fields)}), not {kind}")
        )
        return None
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        seen: set[tuple[Loc, str]] = set()
        for err in exc.errors():
            # union branches add type names to loc; keep the part that addresses the data
            loc = tuple(p for p in err["loc"] if not (isinstance(p, str) and "[" in p))
            loc = tuple(p for p in loc if p not in ("str", "list", "function-after"))
            reason = _reason(err)
            if (loc, reason) not in seen:
                seen.add((loc, reason))
                issues.append(source.issue(loc, reason))
        return None


def _open(path: Path, label: str, issues: list[SpecIssue]) -> _Source | None:
    try:
        return _Source(path, label)
    except FileNotFoundError:
        issues.append(SpecIssue(label, "", "file not found"))
    except UnicodeDecodeError as exc:  # a binary file given by mistake: said, not a codec's traceback
        issues.append(
            SpecIssue(label, "", f"not UTF-8 text: byte 0x{exc.object[exc.start]:02x} at offset {exc.start}")
        )
    except OSError as exc:  # a folder, no permission
        issues.append(SpecIssue(label, "", f"cannot read it: {exc.strerror or exc}"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        issues.append(SpecIssue(label, "", f"not valid YAML: {exc}", line))
    return None


def load_file(root: Path | str, rel: str, model: type[M]) -> M:
    """One YAML file of spec/ (`rel` below `root`) validated by its meta-model `model`: the
    dashboard, real-time, external-control and arm tables, each a file of its own.

    Read without aliases; SpecError names the file, the path inside it (with entry names),
    the line and the reason of every problem, as for the RTDE and primary files.
    """
    issues: list[SpecIssue] = []
    source = _open(Path(root) / rel, rel, issues)
    value = _validate(source, model, issues) if source is not None else None
    if issues or value is None:
        raise SpecError(issues or [SpecIssue(rel, "", "nothing to validate")])
    return value  # type: ignore[no-any-return]


def load_spec(root: Path | str | None = None) -> Spec:
    """Load, validate and lint every spec file below `root`; raise SpecError with all issues."""
    base = Path(root) if root is not None else default_spec_root()
    issues: list[SpecIssue] = []
    sources: dict[str, _Source] = {}
    parts: dict[str, Any] = {}
    for part, (rel, model) in SPEC_FILES.items():
        source = _open(base / rel, rel, issues)
        if source is None:
            continue
        sources[part] = source
        parts[part] = _validate(source, model, issues)
    if issues:
        raise SpecError(issues)
    spec = Spec(**parts)
    problems = [*lint_spec(spec), *lint_recipe_id_rules(spec)]
    found = [sources[part].issue(loc, reason) for part, loc, reason in problems]
    if found:
        raise SpecError(found)
    return spec


def load_fields_file(path: Path | str, spec: Spec, against: FieldsFile | None = None) -> FieldsFile:
    """Load a user's extra fields file (the shape of spec/rtde/fields.yaml).

    Names in `against` (the fields already known) count as duplicates.
    """
    issues: list[SpecIssue] = []
    source = _open(Path(path), str(path), issues)
    if source is None:
        raise SpecError(issues)
    extra = _validate(source, FieldsFile, issues)
    if issues:
        raise SpecError([_shaped(issue) for issue in issues])
    found = [source.issue(loc, reason) for loc, reason in lint_fields_file(extra, spec, against)]
    if found:
        raise SpecError(found)
    return extra


FIELDS_SHAPE = "an extra-fields file holds `inputs:` and `outputs:`, lists of fields as spec/rtde/fields.yaml"


def _shaped(issue: SpecIssue) -> SpecIssue:
    """A key at the top of an extra-fields file that is not one: what the file holds instead
    (`my_field: {type: DOUBLE}` said only "unknown key 'my_field'")."""
    top = issue.path and not any(mark in issue.path for mark in ".[")
    if not (top and issue.reason.startswith("unknown key")) and "the file is a mapping" not in issue.reason:
        return issue
    return replace(issue, reason=f"{issue.reason}; {FIELDS_SHAPE}")
