"""The forms of UR's documents `spec import` reads, by the name `--form` takes: a module of its own,
so the CLI names them without loading the readers (rtde_spec.importers) at every start."""

FORMATS = (
    "cb3-text",
    "tab-text",
    "e-series-text",
    "rendered-text",
    "columns-text",
    "markdown",
    "html",
    "xlsx",
    "primary-text",
)
