"""Scenario YAML files shipped with the package (data only)."""
