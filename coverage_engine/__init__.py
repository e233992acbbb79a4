"""The language: ``.osc`` text in, a resolved model and concrete variants out. Imports nothing else of ours.

Subpackages in the order data flows; each imports only the ones below it (checked by import-linter)::

    .osc text ──parse/──▶ syntax tree ──resolve/──▶ model ──variation/──▶ variants (.sce)
                                                      ▲
                                  files/ (.sce, parameter files, the loader) reads and writes them

``parse/``
    ``grammar.lark`` compiled by lark into LALR tables (``tables``), our lexer (``lexer``), the
    indentation post-lexer (``indenter``), the table driver (``lalr``), the one syntax builder
    (``transformer`` with ``transformer_expr``) making the frozen nodes of ``syntax``; ``parser`` is the
    entry point and ``syntax_errors`` the one place parse failures become messages; ``cache`` keeps the
    tables and parsed libraries between runs.
``resolve/``
    ``resolver`` runs the passes: ``imports`` (imported files, libraries found by ``libraries``),
    ``namespace`` (declared ``types``), ``values`` (expressions, instances, external method calls, with the
    type rules of ``operations`` and the constraints of ``keeps``), ``do_body`` (behaviours and modifiers),
    ``checks`` (unused declarations), ``overrides`` (parameter-file values). Out comes ``model``, which
    ``evaluate`` computes at run time and ``printer`` shows.
``files/``
    ``loader`` (a scenario file in, a model out: the one call the executor needs), ``sce`` (the variant
    format), ``parameters`` (parameter files and their template).
``variation/``
    ``dimensions`` → ``template`` → ``plan`` (each value checked once) → ``output`` (``.sce`` files via ``writer``).

``coverage/``
    the coverage of runs: each run's ``coverage.json`` merged into one graded model, with its text, JSON
    and HTML renderers (its map is in its ``__init__``); it reads results, never the language pipeline.

Below them: ``errors`` (the one exception tree; every error carries a ``location``), ``location``,
``domains`` (what a variation declared per varied parameter: the ``# domain`` lines of a ``.sce``
header and a batch's ``declared.json``, which the ``.sce`` writer writes and the coverage model reads)
and ``records`` (the ``@record`` decorator of syntax nodes and model records). ``osc/`` holds the standard
``.osc`` libraries (``osc.types``, ``osc.helpers``, ``osc.standard``, ``osc.robotics``).
"""
