"""The shared rules of the project's local web servers: which Host, Origin and Sec-Fetch-Site are ours."""
import pytest

from mbzirc_ros_utils.local_http import SameSitePolicy, parse_json_body, split_host


@pytest.mark.parametrize("value,expected", [
    ("127.0.0.1:8087", ("127.0.0.1", 8087)), ("[::1]:8087", ("::1", 8087)), ("[::1]", ("::1", None)),
    ("LocalHost", ("localhost", None)), ("host:abc", ("host", -1)), ("[::1", ("[::1", -1))])
def test_split_host(value, expected):
    assert split_host(value) == expected


def test_port_bound_policy():
    p = SameSitePolicy("127.0.0.1", 8088)
    assert p.check("localhost:8088") is None and p.check("[::1]:8088") is None
    assert "not allowed" in p.check("localhost:8087") and "not allowed" in p.check("localhost")
    assert "evil.example" in p.check("evil.example:8088")          # DNS rebinding: a foreign name
    assert p.check("127.0.0.1:8088", "http://localhost:8088") is None
    for origin in ("http://evil.example:8088", "null", "https://127.0.0.1:8088", "http://127.0.0.1:9"):
        assert "Origin" in p.check("127.0.0.1:8088", origin), origin
    assert p.check("127.0.0.1:8088", None, "same-origin") is None and p.check("127.0.0.1:8088", None, "none") is None
    for site in ("cross-site", "same-site"):
        assert "Sec-Fetch-Site" in p.check("127.0.0.1:8088", None, site)


def test_any_port_policy_and_extra_names():
    p = SameSitePolicy("0.0.0.0", None, ["gcs-laptop", "[fd00::5]", "10.0.0.5:8087"])
    for host in ("127.0.0.1", "localhost:1", "gcs-laptop:8087", "[fd00::5]:80", "10.0.0.5:8087"):
        assert p.check(host) is None, host
    for host in ("0.0.0.0:8087", "10.0.0.5:8088", "10.0.0.5", None, ""):
        assert p.check(host) is not None, host


@pytest.mark.parametrize("ctype,length,body,ok", [
    ("application/json", "2", b"{}", True), ("application/json; charset=utf-8", "2", b"{}", True),
    ("text/plain", "2", b"{}", False), (None, "2", b"{}", False), ("application/json", None, b"{}", False),
    ("application/json", "99999999", b"{}", False), ("application/json", "3", b"{x}", False),
    ("application/json", "2", b"[]", False)])
def test_json_body(ctype, length, body, ok):
    obj, why = parse_json_body(ctype, length, lambda n: body[:n])
    assert (obj is not None) == ok and (why == "") == ok
