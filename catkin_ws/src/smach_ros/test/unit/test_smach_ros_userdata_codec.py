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


# ---- what we send: unpicklable, excluded and oversized keys (upstream #18, #77) ----------------------
def test_excluded_keys_are_left_out_and_big_values_summarised():
    import subprocess
    proc = subprocess.Popen(["true"])
    proc.wait()
    text = encode_local_data({"proc": proc, "secret": "s", "big": "x" * 5000, "n": 2}, exclude=["secret"],
                             max_value_bytes=1000)
    data = decode_local_data(text)
    assert set(data) == {"proc", "big", "n"}
    assert data["proc"].startswith("<unpicklable Popen") and data["n"] == 2
    assert "over the 1000-byte cap" in data["big"]


def test_encode_never_raises_on_hostile_values():
    class Hostile:
        def __reduce__(self):
            raise RuntimeError("no")

        def __repr__(self):
            raise RuntimeError("nor this")

    data = decode_local_data(encode_local_data({"h": Hostile(), (1, Hostile()): 3}))
    assert data["h"].startswith("<unpicklable Hostile")


# ---- decoder limits (found by probing) ----------------------------------------------------------------
def _shared_dag(depth):
    """A pickle of a few hundred bytes whose tree form has 2**depth leaves (each level refers twice to the
    level below)."""
    node = ["leaf"]
    for _ in range(depth):
        node = [node, node]
    return base64.b64encode(pickle.dumps({"k": node}, 2)).decode()


def test_shared_references_are_linear_not_exponential():
    import time
    text = _shared_dag(45)
    assert len(text) < 1000
    start = time.process_time()
    data = decode_local_data(text)      # 46 distinct lists: accepted (depth 46 < 50)
    assert not contains_opaque(data)
    plain = to_plain(data, max_depth=60, max_values=5000)
    assert "<truncated>" in json_dumps(plain)
    assert time.process_time() - start < 2.0


def json_dumps(obj):
    import json
    return json.dumps(obj)


def test_depth_and_size_caps_give_clear_errors():
    from smach_ros.userdata_codec import MAX_DEPTH, check_limits
    deep = []
    for _ in range(MAX_DEPTH + 5):
        deep = [deep]
    with pytest.raises(DecodeError, match="deeper"):
        decode_local_data(base64.b64encode(pickle.dumps({"d": deep}, 2)).decode())
    with pytest.raises(DecodeError, match="deeper"):
        decode_local_data('{"d": ' + "[" * 60 + "]" * 60 + "}")
    with pytest.raises(DecodeError, match="JSON"):
        decode_local_data('{"d": ' + "[" * 100000 + "]" * 100000 + "}")
    with pytest.raises(DecodeError, match="more than 10 values"):
        check_limits({"k": list(range(20))}, max_values=10)


def test_cycles_are_handled():
    loop = []
    loop.append(loop)
    data = decode_local_data(base64.b64encode(pickle.dumps({"l": loop}, 2)).decode())
    assert not contains_opaque(data)
    assert to_plain(data) == {"l": ["<cycle>"]}


def test_class_names_are_capped_per_payload_and_cache_is_bounded():
    from smach_ros import userdata_codec as codec

    # a payload naming more distinct classes than the cap is refused
    names = [("mod%d" % i, "Cls") for i in range(codec.MAX_CLASSES_PER_PAYLOAD + 1)]
    raw = b"\x80\x02]q\x00(" + b"".join(b"c%s\n%s\n)\x81" % (m.encode(), n.encode()) for m, n in names) + b"e."
    text = base64.b64encode(b"\x80\x02}q\x00X\x01\x00\x00\x00kq\x01" + raw[2:-1] + b"s.").decode()
    with pytest.raises(DecodeError, match="distinct classes"):
        decode_local_data(text)
    # many payloads naming new classes: the cache stays bounded
    for i in range(3 * codec.MAX_CACHED_CLASSES):
        one = b"\x80\x02}q\x00X\x01\x00\x00\x00kq\x01cx%d\nC\n)\x81s." % i
        decode_local_data(base64.b64encode(one).decode())
    assert len(codec._opaque_classes) <= codec.MAX_CACHED_CLASSES


def test_size_arguments_to_bytes_are_refused():
    # bytes(10**10) would allocate 10 GB from a 30-byte payload
    raw = b"\x80\x02}q\x00X\x01\x00\x00\x00kc__builtin__\nbytearray\n\x8a\x05\x00\xe4\x0bT\x02\x85Rs."
    with pytest.raises(DecodeError):
        decode_local_data(base64.b64encode(raw).decode())
    data = decode_local_data(encode_local_data({"b": bytearray(b"ab"), "e": b"", "c": 1j}))
    assert data == {"b": bytearray(b"ab"), "e": b"", "c": 1j} and not contains_opaque(data)
