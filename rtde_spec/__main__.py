"""python -m rtde_spec: the rtde-spec command line."""

try:
    from rtde_spec.cli.main import entry
except KeyboardInterrupt:  # Ctrl-C while the command starts: nothing begun, nothing to say but that
    import sys

    print("interrupted", file=sys.stderr)
    sys.exit(130)

entry()
