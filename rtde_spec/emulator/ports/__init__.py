"""The ports: RTDE, primary/secondary, real-time and dashboard servers, the interpreter socket,
and the state messages they send."""

# the interpreter socket's port: UR's article "Interpreter mode" and the e-Series Script Directory's
# chapter 13 (here, where the CLI reads it without loading the emulator)
INTERPRETER_PORT = 30020
