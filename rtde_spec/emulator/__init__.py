"""A controller emulator built from the spec: RTDE and the primary/secondary ports on loopback.

For testing applications where no robot and no URSim container is available.
"""
