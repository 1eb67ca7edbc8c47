"""Every benchmark of ``vmnav bench`` (each prints one JSON object), out of the library.

* ``sim``: physics + rendering frames/s and the camera model's accuracy (``vmnav bench sim``);
* ``vision``, ``localize``: the per-frame pipeline, y/theta and localization on taught
  simulator routes (``vmnav bench vision``); ``features`` and ``state``: features +
  matching and the state estimate on synthetic pairs and scenes (:mod:`sim.synthetic`);
* ``follow``: seeded demos, control laws side by side (``vmnav bench follow``);
* ``log``: the CPU cost of field logging (``vmnav bench log``);
* ``link``, ``link_load``, ``link_vehicles``: the MAVLink link, with simulated vehicles in
  other processes (``vmnav bench link``);
* ``faults``: issue 8's fault cases (:mod:`tools.harness.fault_cases`), each repeated;
* ``fuzz``, ``fuzz_targets``, ``fuzz_inputs``: seeded fuzzing of every decoder and loader
  (``vmnav bench fuzz``, issue 15);
* ``targets``: every benchmark's targets in one table; ``run_all``: ``vmnav bench all``;
* ``cpu``: pinning a benchmark to one core; ``names``: name lists given on the command line.

``tools/bench_cmd.py`` declares the command line; each benchmark module turns its
parsed arguments into a plan (``run(args)``) and measures.
"""
