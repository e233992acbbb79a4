"""The suffixes of scenario files, defined once: what the loader, the batch, the variation and the pytest
plugin accept, and what a variant file is named with."""

from __future__ import annotations

#: An OpenSCENARIO DSL 2 source file.
OSC_SUFFIX = ".osc"

#: A variant written by ``scenario_variation`` (our own format, loadable like its ``.osc``).
SCE_SUFFIX = ".sce"

#: Every suffix a scenario file may have.
SCENARIO_SUFFIXES = (OSC_SUFFIX, SCE_SUFFIX)
