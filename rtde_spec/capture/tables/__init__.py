"""Tables: rows, the sinks they go to, and the summary of what a capture gave and lost."""
