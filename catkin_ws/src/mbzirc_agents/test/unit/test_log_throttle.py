"""ros_backend.CallSiteThrottle: each line of agent code that logs has its own period (rospy's throttle,
called through the backend, had one for all of them). A fake clock: no sleeping."""
from mbzirc_agents import ros_backend


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def _log_a(th):
    return th.due(5.0, depth=1)


def _log_b(th):
    return th.due(5.0, depth=1)


def test_a_frequent_message_does_not_silence_another_line():
    clock = Clock()
    th = ros_backend.CallSiteThrottle(clock)
    assert _log_a(th)
    clock.t += 1.0
    assert _log_b(th)              # before: the backend's one rospy call site had just logged: silenced
    assert not _log_a(th) and not _log_b(th)


def test_each_line_logs_again_after_its_period_and_after_time_went_back():
    clock = Clock()
    th = ros_backend.CallSiteThrottle(clock)
    assert _log_a(th)
    clock.t += 4.9
    assert not _log_a(th)
    clock.t += 0.2
    assert _log_a(th)
    clock.t = 1.0                  # a restarted simulation
    assert _log_a(th)


def test_two_lines_of_agent_code_logging_through_the_ros_backend_both_reach_the_log():
    import logging

    import rospy

    from mbzirc_agents.ros_backend import RosBackend

    rospy.rostime.set_rostime_initialized(True)   # wall time: no master needed
    seen = []

    class Keep(logging.Handler):
        def emit(self, record):
            seen.append(record.getMessage())

    logger = logging.getLogger('rosout')
    handler, level = Keep(), logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        be = RosBackend()
        for _ in range(2):
            be.loginfo_throttle(2.0, 'progress: passing')                      # a task's progress line
            be.loginfo_throttle(5.0, 'clearance guard: vertical speed +0.30')  # before: silenced by it
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    assert [m for m in seen if 'progress' in m or 'clearance' in m] == \
        ['progress: passing', 'clearance guard: vertical speed +0.30']
