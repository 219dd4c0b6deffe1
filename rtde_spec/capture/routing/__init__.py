"""Routing: which connection a segment belongs to, what it speaks, and how long its state is kept."""
