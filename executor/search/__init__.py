"""The search loop of ``scenario_search``: vary, run, read, vary again, until the budget or the goal.

``request``
    the command line's options as one value (:class:`~executor.search.request.SearchRequest`), and what of
    them is kept in the search's ``search.json`` for ``--resume``.
``rounds``
    one round: its variants (``scenario_variation`` in-process) and its batch (the batch machinery in-process).
``loop``
    the rounds one after another, the budget, Ctrl-C and ``--resume``, the progress lines.

What a search leaves behind, and how it reads back, is :mod:`coverage_engine.search_record`.
"""
