"""The language: ``.osc`` text in, a resolved model and concrete variants out. Imports nothing else of ours.

Subpackages in the order data flows; each imports only the ones below it (checked by import-linter)::

    .osc text ──parse/──▶ syntax tree ──resolve/──▶ model ──variation/──▶ variants (.sce)
                                                      ▲
                                  files/ (.sce, parameter files, the loader) reads and writes them

    runs' test.xml + coverage.json ──results/──▶ verdicts, samples ──coverage/──▶ graded model ──▶ text | JSON | HTML

``parse/``
    ``grammar.lark`` compiled by lark into LALR tables (``tables``), our lexer (``lexer``), the
    indentation post-lexer (``indenter``), the table driver (``lalr``), the one syntax builder
    (``transformer`` with ``transformer_expr``, ``parts`` naming each rule's parts, ``strings`` for
    literals) making the frozen nodes of ``syntax``; ``raw`` is one parse without messages, ``parser``
    the entry point and ``syntax_errors`` the one place parse failures become messages; ``cache`` keeps
    the tables and parsed libraries between runs.
``resolve/``
    ``resolver`` runs the passes: ``imports`` (imported files, libraries found by ``libraries``),
    ``namespace`` (declared ``types``), ``values`` (expressions, instances, external method calls, with the
    type rules of ``operations`` and the constraints of ``keeps``), ``do_body`` (behaviours and modifiers),
    ``coverage_items`` (``cover()``/``record()``), ``checks`` (unused declarations), ``overrides``
    (parameter-file values); ``scope`` is what a pass knows while it works. Out comes ``model``, which
    ``evaluate`` computes at run time and ``printer`` shows.
``files/``
    ``loader`` (a scenario file in, a model out: the one call the executor needs), ``sce`` (the variant
    format: ``sce_writer`` writes it, ``sce_plain`` reads it without YAML), ``parameters`` (parameter
    files and their template).
``variation/``
    the variation generator, in passes (see its ``__init__``): dimensions, template, plan, conditions,
    strategies (full, t-way with ``pairwise``, samples ``drawn`` lazily), output.
``results/``
    what runs and batches report: the JUnit document, its names, the one reader, the verdicts, the
    result file names and the one atomic writer (used by the runtime, the batch, ``coverage/`` and the
    pytest plugin).
``coverage/``
    each run's ``coverage.json`` and verdict merged into one graded coverage model, and its three renderers;
    it reads results and ``domains``, never the language pipeline (its map is in its ``__init__``).

Below them: ``errors`` (the one exception tree of every package, rooted at ``UserError``: an error carries
its ``location`` when it has one), ``location`` (a place in a file, or the whole file),
``domains`` (what a variation declared per varied parameter: the ``# domain`` lines of a ``.sce``
header and a batch's ``declared.json``, which the ``.sce`` writer writes and the coverage model reads),
``records`` (the ``@record`` decorator of syntax nodes and model records) and ``suffixes`` (``.osc``,
``.sce``). Beside them: ``yaml_bounds`` (the one bounded YAML loader), ``limits`` (input bounds),
``printable`` (text made safe to show) and ``lazy`` (values computed when asked for). ``osc/`` holds the
standard ``.osc`` libraries (``osc.types``, ``osc.helpers``, ``osc.standard``, ``osc.robotics``).
"""
