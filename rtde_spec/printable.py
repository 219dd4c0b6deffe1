"""Text from the wire made safe for a terminal or a log: control characters shown, never obeyed.

A controller's or client's text message, a program name, a dashboard line can hold escape
sequences that recolour, retitle or rewrite a terminal. Everything that prints or logs
such text passes it through `safe_text` first.
"""

from __future__ import annotations

import logging
import re

# C0 controls (tab and newline included: one message stays one line), DEL and C1 controls
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


def safe_text(text: str) -> str:
    """Control characters as visible escapes (ESC -> \\x1b), so wire text cannot drive the terminal."""
    return _CONTROL.sub(lambda m: f"\\x{ord(m.group()):02x}", text)


class SafeFormatter(logging.Formatter):
    """A log formatter whose lines carry no control characters from their arguments."""

    def formatMessage(self, record: logging.LogRecord) -> str:
        return safe_text(super().formatMessage(record))
