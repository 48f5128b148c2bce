"""Robustness harness of the MBZIRC C3 system: fuzzer, network-namespace hosts, fault scenarios, report."""
