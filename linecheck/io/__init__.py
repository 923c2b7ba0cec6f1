"""Input/output shared by every front end (no UI imports): atomic writes, JSON."""
