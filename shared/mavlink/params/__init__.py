"""The parameter protocol (devguide parameter.md): the vehicle's parameters, read and set by a GCS.

::

    list  GCS PARAM_REQUEST_LIST -> vehicle PARAM_VALUE(i, count) for every i, paced
          GCS PARAM_REQUEST_READ(index=i) for each i it missed -> PARAM_VALUE(i)
    read  GCS PARAM_REQUEST_READ(name, index=-1) -> PARAM_VALUE(name)
    set   GCS PARAM_SET(name, value) -> PARAM_VALUE(name, value now in force)

* ``table``: :class:`~shared.mavlink.params.table.ParamTable`, declared parameters
  and their values, and how a name and a value go on the wire (both ends);
* ``vehicle``: :class:`~shared.mavlink.params.vehicle.ParamServer`, the vehicle's
  end (streams the list, echoes every set, refuses bad values);
* ``gcs``: :class:`~shared.mavlink.params.gcs.ParamClient`, the ground station's
  end (fetches all, gets and sets one, with retries).

The robot's own parameters, bound to its config, and their file are robot-only:
``robot/vehicle/robot_params.py`` and ``robot/vehicle/param_file.py``.
"""
