"""A backend with no ROS: lets the framework run in unit tests (threads on a simulated clock, see
sim_clock.py: no test waits in wall time)."""
import threading

from sim_clock import SimClock


class FakeServer:
    """Stands in for actionlib.SimpleActionServer: send() runs execute_cb in a thread."""

    def __init__(self, name, execute_cb, clock):
        self.name = name
        self.clock = clock
        self.execute_cb = execute_cb
        self.status = None
        self.result = None
        self.text = ''
        self.feedback = []
        self.preempt = False
        self.done = threading.Event()

    def send(self, goal):
        self.status, self.preempt = None, False
        self.done.clear()
        self.clock.start_thread(self._run, goal, name=f'{self.name} goal')

    def _run(self, goal):
        self.execute_cb(goal)
        self.done.set()

    def wait(self, timeout=5.0):
        """The status once done; fails after `timeout` simulated seconds."""
        assert self.clock.wait(self.done, timeout), f'{self.name} did not finish in {timeout} s'
        return self.status

    def is_preempt_requested(self):
        return self.preempt

    def set_succeeded(self, result=None, text=''):
        self.status, self.result, self.text = 'succeeded', result, text

    def set_aborted(self, result=None, text=''):
        self.status, self.result, self.text = 'aborted', result, text

    def set_preempted(self, result=None, text=''):
        self.status, self.result, self.text = 'preempted', result, text

    def publish_feedback(self, fb):
        self.feedback.append(fb)


class FakeSubscription:
    """What backend.subscriber returns: unregister() stops the messages (as rospy.Subscriber's)."""

    def __init__(self, subs, topic, cb):
        self.subs, self.topic, self.cb = subs, topic, cb

    def unregister(self):
        if self.subs.get(self.topic) is self.cb:
            del self.subs[self.topic]


class FakeBackend:
    def __init__(self):
        self.clock = SimClock()
        self._shutdown = False
        self.subs = {}
        self.services = {}
        self.servers = {}
        self.pubs = {}
        self.errors = []
        self.infos = []
        self.warns = []
        self.handlers = {}          # service name -> callable(request) for service_proxy

    def subscriber(self, topic, msg_type, cb):
        """Messages of topic go to cb (self.subs[topic]) until the returned subscription is unregistered."""
        self.subs[topic] = cb
        return FakeSubscription(self.subs, topic, cb)

    def publisher(self, topic, msg_type, latch=False):
        self.pubs[topic] = []
        return type('P', (), {'publish': lambda s, m, t=topic: self.pubs[t].append(m)})()

    def service(self, name, srv_type, handler):
        self.services[name] = handler

    def service_proxy(self, name, srv_type):
        def call(*args, **kwargs):
            if name not in self.handlers:
                raise RuntimeError(f'service {name} not available')
            req = args[0] if args else srv_type._request_class(**kwargs)
            return self.handlers[name](req)
        return call

    def action_server(self, name, action, execute_cb):
        s = FakeServer(name, execute_cb, self.clock)
        self.servers[name] = s
        return s

    def timer(self, period, cb):
        return None

    def now(self):
        return self.clock.now()

    def sleep(self, s):
        self.clock.sleep(s)

    def start_thread(self, name, target):
        return self.clock.start_thread(target, name=name)

    def wall_time(self):
        return self.clock.now()

    def wait_event(self, event, timeout):
        return self.clock.wait(event, timeout)

    @property
    def shutdown(self):
        return self._shutdown

    @shutdown.setter
    def shutdown(self, value):
        """Ctrl+C: also stops the clock, so that every thread waiting on it wakes and sees it."""
        self._shutdown = bool(value)
        if value:
            self.clock.stop()

    def is_shutdown(self):
        return self._shutdown

    def loginfo(self, m):
        self.infos.append(m)

    def loginfo_throttle(self, p, m):
        pass

    def logerr_throttle(self, p, m):
        self.errors.append(m)

    def logerr(self, m):
        self.errors.append(m)

    def logwarn(self, m):
        self.warns.append(m)
