"""Files around the language: scenario files loaded into a model, ``.sce`` variants, scenario parameter files.

Entry point for the executor and the commands: :func:`~coverage_engine.files.loader.load_scenario_file`.

``loader``
    a scenario file (``.osc`` or ``.sce``) in, a resolved model out.
``sce`` / ``sce_writer`` / ``sce_plain``
    the variant format: read with YAML, written from a template per source, read without YAML.
``sce_domains``
    the ``# domain`` lines of a ``.sce`` header: what the variation declared for each varied parameter.
``parameters``
    scenario parameter files and the template of all overridable parameters.
"""
