"""Adaptive search over recorded results: read earlier runs of one source, propose the next variants.

The strategies ``boundary``, ``falsify`` and ``fill-holes`` of ``scenario_variation --from RESULTS`` are
pure functions here: they take the axes of the variation (:mod:`.space`), the runs read back
(:mod:`.history`) and the options, and return points of the unit cube (one coordinate per axis) with
what the round estimated (:mod:`.estimate`). The variation pipeline turns the points into variants like
any sampler's; nothing here runs a scenario, forks or waits (ask/tell: the batch runs the proposals).
"""
