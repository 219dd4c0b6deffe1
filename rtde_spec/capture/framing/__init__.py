"""Framing: one direction's reassembled bytes cut into packages, records or lines."""
