"""The ports: RTDE, primary/secondary, real-time and dashboard servers, and the state messages they send."""
