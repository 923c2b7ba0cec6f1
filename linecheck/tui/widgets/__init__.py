"""Views of the TUI's main tabs."""
