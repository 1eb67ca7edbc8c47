"""Figures computed after the fact from a run or a log: numbers and matplotlib plots.

Nothing here drives a robot, a simulator or a ground station; it reads what they left.

* ``log_plot``: the paper-style figures of any robot log (``vmnav log plot``);
* ``demo_report``: the demo's errors against the simulator's truth (``report.json``,
  also ``vmnav bench follow``'s figures);
* ``demo_plots``: the demo's plots and video.
"""
