"""Lint of the RTDE protocol facts beside the layouts: which data packages carry the recipe id."""

from __future__ import annotations

from collections.abc import Iterator

from rtde_spec.metamodel.schema import Spec

Loc = tuple[str | int, ...]


def lint_recipe_id_rules(spec: Spec) -> Iterator[tuple[str, Loc, str]]:
    """Each (sender, protocol) has at most one rule, and only senders and protocols that exist."""
    protocols = {p for m in spec.packages.messages for p in m.protocols}
    seen: dict[tuple[str, int], int] = {}
    for i, rule in enumerate(spec.packages.data_recipe_id):
        loc: Loc = ("data_recipe_id", i)
        for sender in rule.senders:
            if sender not in spec.packages.senders:
                yield "packages", (*loc, "senders"), f"unknown sender {sender!r}"
        for proto in rule.protocols:
            if proto not in protocols:
                yield "packages", (*loc, "protocols"), f"no message is of protocol {proto}"
            for sender in rule.senders:
                if (sender, proto) in seen:
                    yield (
                        "packages",
                        (*loc, "protocols"),
                        f"{sender} in protocol {proto} already has rule {seen[(sender, proto)]}",
                    )
                seen[(sender, proto)] = i
