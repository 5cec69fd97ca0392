"""Fixtures of the Mitsuba plugin's tests (defined in mitsuba_helpers, which tests import)."""
from mitsuba_helpers import vector_table, vectors  # noqa: F401
