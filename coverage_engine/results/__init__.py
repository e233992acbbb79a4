"""Results: what a run or a batch reports, in one room used by the runtime, the batch, the coverage model
and the pytest plugin. Imports nothing of ours but ``coverage_engine.domains`` (how a drawn value is
shown in a testcase name) and ``coverage_engine.printable``.

``files``
    the names of the files a run leaves in its folder (``test.xml``, ``log.txt``, ``coverage.json``,
    ``declared.json``): each defined once.
``document``
    the JUnit document in the form CI tools validate (Jenkins' ``junit-10.xsd``): testcases, suites,
    totals computed from the testcases, every value escaped by ElementTree.
``names``
    how testcases and suites are named (classname the source scenario, name the variant with its values).
``scenario_result`` / ``run_report``
    one executed scenario's outcome, and the ``test.xml`` of a ``scenario_execution`` run built from them.
``read``
    the one reader of JUnit XML (defusedxml: a child's XML is untrusted), streamed suite by suite, with the
    one :class:`~coverage_engine.results.read.JunitUnreadable`.
``verdicts``
    the one verdict enum and how testcases fold into a run's verdict.
``atomic``
    the one atomic file writer (temporary name in the folder, renamed over the target, never through a link).

The batch's merged report (:mod:`executor.batch.junit_merge`) builds its document with these parts; it
stays in the batch because it reads the store's jobs.
"""
