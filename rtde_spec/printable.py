"""Text from the wire made safe for a terminal or a log: control characters shown, never obeyed.

A controller's or client's text message, a program name, a dashboard line can hold escape
sequences that recolour, retitle or rewrite a terminal. Everything that prints or logs
such text passes it through `safe_text` first.
"""

from __future__ import annotations

import logging
import re

# C0 controls (tab and newline included: one message stays one line), DEL and C1 controls, the
# line and paragraph separators, and lone surrogates (undecodable bytes kept by surrogateescape:
# no stream can encode them, and a log record holding one breaks whatever serialises it)
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\ud800-\udfff]")


def _escape(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"


def safe_text(text: str) -> str:
    """Control characters as visible escapes (ESC -> \\x1b, a lone surrogate -> \\udcff), so wire
    text cannot drive the terminal, nor break a stream or a log."""
    return _CONTROL.sub(_escape, text)


class SafeFormatter(logging.Formatter):
    """A log formatter whose lines carry no control characters from their arguments."""

    def formatMessage(self, record: logging.LogRecord) -> str:
        return safe_text(super().formatMessage(record))
