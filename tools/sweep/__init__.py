"""``vmnav sweep``: many lock-step demos over a plan's axes, on local processes or on Ray
(docs/sweeps.md).

* ``plan``: the plan file and the cases it expands to (each a ``vmnav demo`` command line);
  ``plan_check``: every value checked before any case runs;
* ``case``: what a worker runs (teach a memory, repeat a case), plain picklable functions;
* ``executors``: this process, a local pool, Ray; ``runner``: the loop (teach first, then
  the cases, rows as they end);
* ``results``: the sweep's folder (plan, code version, ``results.csv``) and resumption;
* ``report`` and ``stats``: the Markdown report, Wilson and Poisson intervals, CDFs.
"""
