"""Interactive terminal UI (Textual) -- ``linecheck tui``.

A thin front end over :mod:`linecheck.service`: it never calls the solver
directly.  Layout:

- ``app.py``: the application (tabs, key bindings, run worker, exports);
- ``messages.py``: the typed messages the app posts (tests record them);
- ``catalog.py``, ``formatting.py``, ``figures.py``, ``runner.py``: plain Python
  (no Textual) -- case discovery, table text, plot data, the run job;
- ``plotting.py``: the one adapter over textual-plotext;
- ``widgets/`` and ``screens/``: the views and the modal dialogs;
- ``app.tcss``: all styles.

Importing this package does not import Textual; ``linecheck.tui.app`` does.
"""
