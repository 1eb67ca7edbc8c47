"""The code that wires two of robot/, sim/ and ground/ together (the only place that does).

* ``sim_args``: the command-line options of the commands that build a simulated world;
* ``teach``: teach a route in the simulator in lock-step, keeping the true poses;
* ``demo``: the demo's scenario, its taught memory and its lock-step repeat;
  ``lockstep_pioneer``: the robot's Pioneer driver on the emulated Pioneer, in lock-step;
  ``ground_dispatch``: the ground station that sends the repeat its goal;
  ``demo_log``: the robot's field log plus the simulator's truth;
* ``hil_demo``: the demo as separate processes (simulator, ``vmnav robot``, ground station);
* ``hil_rig``, ``fault_cases``, ``fault_garbage``: the hardware-in-the-loop rig and issue 8's
  fault cases on it; ``short_routes``: the short routes they teach;
* ``vmnav_process``: a ``vmnav`` command as a child process.
"""
