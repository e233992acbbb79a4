"""Example action library for scenario_execution (see README.md)."""
