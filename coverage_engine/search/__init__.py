"""Adaptive search over recorded results: read earlier runs of one source, propose the next variants.

The strategies ``boundary``, ``falsify`` and ``fill-holes`` of ``scenario_variation --from RESULTS`` are
pure functions here: they take the axes of the variation (:mod:`.space`), the runs read back
(:mod:`.history`) and the options (what to look for: :mod:`.target`), and return points of the unit cube (one coordinate per axis) with
what the round estimated (:mod:`.estimate`). The variation pipeline turns the points into variants like
any sampler's; nothing here runs a scenario, forks or waits (ask/tell: the batch runs the proposals).
"""

#: The adaptive strategies of ``scenario_variation --from`` (the goals of the search loop). Kept here, in a
#: module that imports nothing, so the command line can list them without loading the search.
ADAPTIVE = ("boundary", "fill-holes", "falsify")

#: Default of ``--resolution``: a boundary is located to 1 % of each range.
DEFAULT_RESOLUTION = 0.01
