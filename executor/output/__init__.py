"""What the commands that write results share about their output.

``folder_lock``
    one writer per output folder: ``scenario_variation -o`` and ``scenario_batch_execution -o`` hold
    a ``flock`` on ``.scenario-lock`` that names its holder.
``terminal``
    the one terminal policy (rich on a real terminal, plain lines in pipes and files) and
    :func:`~executor.output.terminal.printable`, which escapes control characters before they are shown.
"""
