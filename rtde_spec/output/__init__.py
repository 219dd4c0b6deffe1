"""What decoded values become: text for people, tables and streaming files for tools."""
