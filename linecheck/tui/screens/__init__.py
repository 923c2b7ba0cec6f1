"""Modal screens: help, error, file-name prompt."""
