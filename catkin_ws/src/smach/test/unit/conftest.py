"""Shared fixtures: quiet smach logging, record it, and reset the shutdown check."""
import pytest

import smach


@pytest.fixture(autouse=True)
def quiet_logs():
    records = {"info": [], "warn": [], "debug": [], "error": []}
    smach.set_loggers(records["info"].append, records["warn"].append, records["debug"].append,
                      records["error"].append)
    smach.set_shutdown_check(lambda: False)
    yield records
    smach.set_shutdown_check(lambda: False)
