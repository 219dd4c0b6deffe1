"""RTDE (port 30004): package models and codec, the session state machine."""
