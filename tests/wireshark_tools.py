"""Wireshark's command-line tools the capture tests run (tshark, dumpcap, editcap, mergecap: the
Debian package tshark, which .ci/run installs). Under CI a missing one fails the module that needs
it, so a runner without them cannot pass by skipping; elsewhere it skips the module."""

from __future__ import annotations

import os
import shutil

import pytest


def wireshark_tool(name: str, untested: str = "") -> str:
    """The path of `name`; `untested` says what goes untested without it."""
    found = shutil.which(name)
    if found is None:
        reason = f"{name} is not installed (Debian package tshark; .ci/run installs it){untested}"
        if os.environ.get("CI"):
            pytest.fail(reason, pytrace=False)
        pytest.skip(reason, allow_module_level=True)
    return found
