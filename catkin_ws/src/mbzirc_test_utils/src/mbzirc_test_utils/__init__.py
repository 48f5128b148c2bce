"""Helpers shared by the rostests of several packages (written once instead of once per test file)."""
