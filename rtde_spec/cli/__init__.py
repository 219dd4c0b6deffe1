"""The rtde-spec command line: one module per subcommand."""
