"""``vmnav ground web``: the ground station as a web app, served by the station's own process.

Parts, one concern each:

* :mod:`ground.web.vehicle_json` and :mod:`ground.web.link_quality`: what the page shows of
  each vehicle, from the station's :class:`~ground.fleet.Fleet` and its packets (pure);
* :mod:`ground.web.requests`: the page's requests, checked (pure);
* :mod:`ground.web.station_loop`: the one thread that owns the
  :class:`~ground.station.GroundStation` (the loop);
* :mod:`ground.web.app`: the Starlette app, its WebSocket and the HTTP routes (adapter);
* :mod:`ground.web.server`: uvicorn on a socket, started and stopped with the loop;
* ``static/``: the page, plain ES modules, no build step.
"""
