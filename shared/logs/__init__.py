"""Field logs in MCAP: what the robot and the ground station record, and tools to read them.

Modules:

* ``schemas``: JSON Schemas of every message (Foxglove well-known types, our flat
  ones, MAVLink per message type); ``topics``: topic and frame names;
  ``messages``: pure builders of the messages.
* ``writer``: :class:`~shared.logs.writer.LogWriter`, a bounded queue and a writer
  thread (``_mcap_files`` owns the files: rotation, flushing, error handling);
  ``retention``: the log folder's size and age limits, applied as files open. Stamps
  are Unix time; each file records its clock's offset (``topics.CLOCK_METADATA``).
* ``reader``: ``log_info``, ``read_messages``, ``read_metadata`` and ``recover`` for
  finished, unfinished and damaged files (``_scan`` walks records robustly);
  ``series``: the files of a rotated log in order (``log_series``).
* ``bench``: the CPU cost of logging, for ``vmnav bench log``.
"""
