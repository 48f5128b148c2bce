"""The probes' stimulus publisher: a node of its own, so that its connections are not the fuzzer's.

Why: a rospy subscriber that receives one message it cannot deserialize (the fuzzer's byte garbage) drops
that publisher's connection and never gets a message from it again: the bad bytes stay in the
connection's read buffer, so every reconnection's handshake fails (measured: deaf for > 50 s, README
Findings). Every publisher of one process shares one connection per subscriber, so a stimulus sent by the
fuzzer's own process after its garbage would never arrive, and a node that works fine would look broken.

Protocol: one JSON line per message on stdin, ``{"topic": ..., "type": ..., "payload": base64 of the
serialized message}``; published in order; the process ends at end of input.
Run: ``python3 -m mbzirc_robustness.probe_sender`` (ProbeRunner's RosBus starts it).
"""
from __future__ import annotations

import base64
import json
import sys
import time

CONNECT_WAIT_S = 2.0   # a new publisher: let the subscribers connect before its first message


def main() -> None:
    import rospy

    from mbzirc_robustness.fuzz import message_class
    from mbzirc_robustness.fuzz_runner import raw_message_class
    rospy.init_node("probe_sender", anonymous=True, disable_signals=True)
    pubs: dict[str, rospy.Publisher] = {}
    for line in sys.stdin:
        try:
            item = json.loads(line)
            pub = pubs.get(item["topic"])
            if pub is None:
                pub = pubs[item["topic"]] = rospy.Publisher(item["topic"], raw_message_class(message_class(item["type"])),
                                                            queue_size=10)
                deadline = time.monotonic() + CONNECT_WAIT_S
                while pub.get_num_connections() == 0 and time.monotonic() < deadline:
                    time.sleep(0.05)
            pub.publish(pub.data_class(base64.b64decode(item["payload"])))
        except Exception as e:  # noqa: BLE001 - one bad line must not end the sender
            rospy.logerr(f"probe_sender: cannot send {line[:80]!r}: {e}")
    rospy.signal_shutdown("end of input")


if __name__ == "__main__":
    main()
