"""A radio set the arrow keys step through at once (no enter needed): the reaction of the
Reactions tab, the load case of the Load trees tab."""

from __future__ import annotations

from textual.widgets import RadioButton, RadioSet


class StepChoice(RadioSet):
    """←/→ (and ↑/↓) press the previous/next button, wrapping around.  Before a button is
    pressed (RadioSet's own mount calls ``action_next_button`` to place its highlight) the keys
    do what RadioSet's do."""

    def step(self, step: int) -> None:
        """Press the button ``step`` places after (before) the pressed one."""
        buttons = list(self.query(RadioButton))
        i = max(self.pressed_index, 0)
        buttons[(i + step) % len(buttons)].value = True

    def action_next_button(self) -> None:
        if self.pressed_index < 0:
            super().action_next_button()
        else:
            self.step(1)

    def action_previous_button(self) -> None:
        if self.pressed_index < 0:
            super().action_previous_button()
        else:
            self.step(-1)
