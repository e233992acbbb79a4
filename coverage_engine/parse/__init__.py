"""Parsing: ``.osc`` text → the syntax tree (frozen :mod:`~coverage_engine.parse.syntax` nodes, no meaning).

Entry points: :func:`~coverage_engine.parse.parser.parse_text`, :func:`~coverage_engine.parse.parser.parse_file`
and, for imported files, :func:`~coverage_engine.parse.parser.parse_file_cached`. This package's
``__init__`` imports nothing, so each entry point costs only what it uses.

``parser`` → ``raw`` (one parse: ``lexer`` → ``indenter`` → ``lalr`` over ``tables`` → ``transformer``
with ``transformer_expr`` and ``strings``) → ``syntax`` nodes; ``syntax_errors`` turns a failure into our
error; ``cache`` keeps tables and parsed libraries in a private per-user folder.
"""
