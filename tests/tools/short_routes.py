"""The short routes of the lab world, for the tests: they live in :mod:`tools.harness.short_routes`
(``vmnav bench faults`` teaches them too)."""

from tools.harness.short_routes import EXTRA_ROUTES, teach_east_a, write_short_routes_world

__all__ = ["EXTRA_ROUTES", "teach_east_a", "write_short_routes_world"]
