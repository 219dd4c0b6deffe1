"""Wire mechanics shared by both protocols: framing, construct helpers, model types."""
