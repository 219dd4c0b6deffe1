"""The spec as data: meta-model (schema), YAML loader, lint, versions, field catalogue."""
