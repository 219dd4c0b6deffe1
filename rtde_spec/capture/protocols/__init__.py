"""Protocols: one decoder per protocol behind the ConnectionDecoder protocol, packages to rows."""
