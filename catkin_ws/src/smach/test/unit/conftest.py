"""Shared fixtures: quiet smach logging, record it, and reset the shutdown check."""
import pytest

import smach


@pytest.fixture(autouse=True)
def quiet_logs():
    saved_loggers = dict(smach.log._loggers)
    saved_check = smach.log._shutdown_check
    records = {"info": [], "warn": [], "debug": [], "error": []}
    smach.set_loggers(records["info"].append, records["warn"].append, records["debug"].append,
                      records["error"].append)
    smach.set_shutdown_check(lambda: False)
    yield records
    smach.log._loggers.update(saved_loggers)  # leave other packages' tests as they were
    smach.set_shutdown_check(saved_check)
