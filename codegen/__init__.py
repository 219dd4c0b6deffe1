"""Compile spec/ into rtde_spec/_generated/ and docs/reference/ (run: python -m codegen)."""
