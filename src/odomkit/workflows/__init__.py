"""Side-effecting workflows behind the CLI: read files, run the core, write outputs.

One module per command, each with the one function its CLI command calls, so the
commands stay thin and everything they do is also available from Python:

- :mod:`odomkit.workflows.track` — ``odomkit track`` (:func:`~odomkit.workflows.track.run_track`);
- :mod:`odomkit.workflows.predict` — ``odomkit predict``;
- :mod:`odomkit.workflows.simulate` — ``odomkit simulate``;
- :mod:`odomkit.workflows.umbmark` — ``odomkit umbmark``;
- :mod:`odomkit.workflows.calibration` — ``odomkit calibrate`` and ``calibrate-noise``;
- :mod:`odomkit.workflows.demo` — ``odomkit demo`` (its page: :mod:`odomkit.workflows.demo_report`);
- :mod:`odomkit.workflows.report` — ``odomkit report``, the HTML page of one log;
- :mod:`odomkit.workflows.logs` — reading a log in any format (shared by the above).

Nothing is imported eagerly here: a command loads only what it runs.
"""

__all__: list[str] = []
