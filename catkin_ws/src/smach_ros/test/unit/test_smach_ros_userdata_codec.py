"""The local_data codec: round trips, JSON, and the safe decoder refusing to run code."""
import base64
import os
import pickle

import pytest

from smach_ros.userdata_codec import (DecodeError, Opaque, contains_opaque, decode_local_data,
                                      encode_local_data, to_plain)


class Point:
    def __init__(self, x):
        self.x = x


class Evil:
    def __reduce__(self):
        return (os.system, ("touch /tmp/smach_codec_pwned",))


def test_plain_round_trip_is_pickle_protocol_2_base64():
    data = {"a": 1, "b": [1.5, "x", None, True], "c": {"n": (1, 2)}, "d": b"\x00\xff", "e": {1, 2}}
    text = encode_local_data(data)
    raw = base64.b64decode(text)
    assert raw[:2] == b"\x80\x02"  # protocol 2, what Noetic viewers expect
    assert pickle.loads(raw) == data
    assert decode_local_data(text) == data


def test_json_object_accepted():
    assert decode_local_data('{"a": [1, 2], "b": "x"}') == {"a": [1, 2], "b": "x"}
    assert decode_local_data("") == {}


def test_malicious_pickle_is_not_executed():
    path = "/tmp/smach_codec_pwned"
    if os.path.exists(path):
        os.remove(path)
    text = base64.b64encode(pickle.dumps({"k": Evil()}, 2)).decode()
    data = decode_local_data(text)
    assert not os.path.exists(path)
    assert isinstance(data["k"], Opaque)
    assert contains_opaque(data)
    assert to_plain(data)["k"]["__class__"] in ("posix.system", "nt.system")


def test_user_objects_become_opaque_records_with_state():
    text = encode_local_data({"p": Point(3)})
    data = decode_local_data(text)
    assert isinstance(data["p"], Opaque)
    plain = to_plain(data)
    assert plain["p"]["__class__"].endswith("Point")
    assert plain["p"]["state"] == {"x": 3}


def test_unsafe_mode_restores_real_objects():
    text = encode_local_data({"p": Point(3)})
    assert decode_local_data(text, allow_unsafe=True)["p"].x == 3


def test_unpicklable_values_become_text():
    import threading
    text = encode_local_data({"lock": threading.Lock(), "n": 1})
    data = decode_local_data(text)
    assert data["n"] == 1 and data["lock"].startswith("<unpicklable")


@pytest.mark.parametrize("bad", ["%%%notbase64", base64.b64encode(b"garbage").decode(),
                                 base64.b64encode(pickle.dumps([1, 2], 2)).decode(), "{not json", "[1]x"])
def test_malformed_raises_decode_error(bad):
    with pytest.raises(DecodeError):
        decode_local_data(bad)


def test_to_plain_handles_nan_and_bytes():
    out = to_plain({"f": float("nan"), "b": b"ab", "big": b"x" * 100})
    assert out == {"f": "nan", "b": "b'ab'", "big": "<100 bytes>"}
