"""Files around the language: scenario files loaded into a model, ``.sce`` variants, scenario parameter files.

Entry point for the executor and the commands: :func:`~coverage_engine.files.loader.load_scenario_file`.
"""
