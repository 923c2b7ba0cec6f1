"""Names shared by the computation and every front end: the reaction components."""

from __future__ import annotations

#: The reaction components at a tower, in array order (axis 2 of the reaction arrays): Rx along
#: the line, Ry across it, Rz vertical (each tower in its own frame) [N].
REACTIONS: tuple[str, str, str] = ("Rx", "Ry", "Rz")
