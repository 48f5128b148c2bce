"""A backend with no ROS: lets the framework run in unit tests (threads, wall time)."""
import threading
import time


class FakeServer:
    """Stands in for actionlib.SimpleActionServer: send() runs execute_cb in a thread."""

    def __init__(self, name, execute_cb):
        self.name = name
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
        threading.Thread(target=self._run, args=(goal,), daemon=True).start()

    def _run(self, goal):
        self.execute_cb(goal)
        self.done.set()

    def wait(self, timeout=5.0):
        assert self.done.wait(timeout), f'{self.name} did not finish'
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


class FakeBackend:
    def __init__(self):
        self.subs = {}
        self.services = {}
        self.servers = {}
        self.pubs = {}
        self.errors = []
        self.infos = []
        self.shutdown = False
        self.handlers = {}          # service name -> callable(request) for service_proxy

    def subscriber(self, topic, msg_type, cb):
        self.subs[topic] = cb

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
        s = FakeServer(name, execute_cb)
        self.servers[name] = s
        return s

    def timer(self, period, cb):
        return None

    def now(self):
        return time.monotonic()

    def sleep(self, s):
        time.sleep(s)

    def is_shutdown(self):
        return self.shutdown

    def loginfo(self, m):
        self.infos.append(m)

    def loginfo_throttle(self, p, m):
        pass

    def logerr_throttle(self, p, m):
        self.errors.append(m)

    def logerr(self, m):
        self.errors.append(m)

    def logwarn(self, m):
        pass
